"""The F-16 ground vibration test loader, on the measured files when present
(``SKLEARN_PNLSS_F16_DATA``, or ``../shared/data/f16``: the ``f16_dir``
fixture of conftest) and on small synthetic files of the same layout
otherwise."""
import numpy as np
import pytest

from sklearn_pnlss.datasets import load_f16

PERIOD = 8192


@pytest.fixture(scope="module")
def level3(f16_dir):
    return load_f16(f16_dir, level=3)


def _rms(x, axis=None):
    return np.sqrt(np.mean(np.square(x), axis=axis))


# -- without the measured files ------------------------------------------------

def test_missing_folder_names_argument_and_variable(monkeypatch, tmp_path):
    monkeypatch.delenv("SKLEARN_PNLSS_F16_DATA", raising=False)
    with pytest.raises(FileNotFoundError, match=r"path=.*SKLEARN_PNLSS_F16_DATA"):
        load_f16()
    with pytest.raises(FileNotFoundError, match=r"F16Data_FullMSine_Level3\.mat.*SKLEARN_PNLSS_F16_DATA"):
        load_f16(tmp_path)
    monkeypatch.setenv("SKLEARN_PNLSS_F16_DATA", str(tmp_path))
    with pytest.raises(FileNotFoundError, match=r"from \$SKLEARN_PNLSS_F16_DATA"):
        load_f16()


@pytest.mark.parametrize("kwargs, match", [
    ({"kind": "chirp"}, "kind must be one of"),
    ({"level": 8}, "level must be an int in 1..7"),
    ({"kind": "special_odd", "level": 4}, "level must be an int in 1..3"),
    ({"level": True}, "level must be an int"),
])
def test_bad_arguments(tmp_path, kwargs, match):
    with pytest.raises(ValueError, match=match):
        load_f16(tmp_path, **kwargs)


def _write_mat(path, force, acc):
    from scipy.io import savemat

    savemat(path, {"Force": force, "Voltage": force / 100.0, "Acceleration": acc,
                   "Fs": np.array([[400.0]])})


def test_special_odd_layout_from_synthetic_files(tmp_path):
    """Realisations in rows, three periods of 16384 samples, the first dropped;
    the tenth realisation comes from the *_Validation file."""
    rng = np.random.RandomState(0)
    n = 3 * 16384
    force = rng.randn(9, n)
    acc = rng.randn(3, 9, n)
    _write_mat(tmp_path / "F16Data_SpecialOddMSine_Level2.mat", force, acc)
    _write_mat(tmp_path / "F16Data_SpecialOddMSine_Level2_Validation.mat", force[:1], acc[:, :1])
    data = load_f16(tmp_path, kind="special_odd", level=2)
    assert data.X.shape == (9, 2 * 16384, 1) and data.y.shape == (9, 2 * 16384, 3)
    assert data.X_raw.shape == (9, n, 1) and data.period == 16384
    np.testing.assert_array_equal(data.X[4, :, 0], force[4, 16384:])
    np.testing.assert_array_equal(data.y[4, :, 2], acc[2, 4, 16384:])
    assert data.X_val.shape == (1, 2 * 16384, 1) and data.validation_level == 2
    np.testing.assert_array_equal(data.voltage[..., 0], force[:, 16384:] / 100.0)


def test_sweep_padding_removed_and_csv_read(tmp_path):
    n = 1000
    t = np.arange(n) / 400.0
    force = np.sin(2 * np.pi * 5 * t)
    force[900:] = 0.0
    acc = np.stack([force, 0.5 * force, -force])
    acc[1, 900:905] = 1e-3  # a channel that still rings after the force stops
    header = '"Force","Voltage","Acceleration1","Acceleration2","Acceleration3","Fs",'
    rows = [f"{f},{f / 100},{a1},{a2},{a3},400," for f, a1, a2, a3 in zip(force, *acc)]
    (tmp_path / "F16Data_SineSw_Level3.csv").write_text("\n".join([header, *rows]) + "\n")
    data = load_f16(tmp_path, kind="sinesweep", level=3, validation_level=None)
    assert data.X.shape == (1, 905, 1) and data.y.shape == (1, 905, 3)
    assert data.X_raw.shape == (1, n, 1) and data.period is None and data.lines is None
    assert data.X_val is None and data.validation_level is None
    np.testing.assert_allclose(data.y[0, :, 1], acc[1, :905])


# -- measured files ------------------------------------------------------------

def test_multisine_layout(level3):
    d = level3
    assert d.X.shape == (1, 8 * PERIOD, 1) and d.y.shape == (1, 8 * PERIOD, 3)
    assert d.X_raw.shape == (1, 9 * PERIOD, 1) and d.y_raw.shape == (1, 9 * PERIOD, 3)
    np.testing.assert_array_equal(d.X, d.X_raw[:, PERIOD:])
    np.testing.assert_array_equal(d.y, d.y_raw[:, PERIOD:])
    assert d.voltage.shape == d.X.shape
    assert d.fs == 400.0 and d.period == PERIOD and d.level == 3 and d.kind == "multisine"
    # test level of the benchmark's pairing, same layout
    assert d.validation_level == 2
    assert d.X_val.shape == (1, 8 * PERIOD, 1) and d.y_val.shape == (1, 8 * PERIOD, 3)
    # nominal levels: 36.8 N rms (estimation), 24.6 N rms (test)
    assert _rms(d.X) == pytest.approx(36.8, rel=0.01)
    assert _rms(d.X_val) == pytest.approx(24.6, rel=0.01)
    assert len(d.output_names) == 3 and "F-16" in d.DESCR


def test_multisine_is_periodic_within_the_noise(level3):
    """Periods 2-9 repeat to about 1 % of the output (measurement noise);
    the dropped first period holds the transient, three to four times
    further from the steady state."""
    y = level3.y[0].reshape(8, PERIOD, 3)
    steady = y.mean(axis=0)
    spread = _rms(y - steady, axis=(0, 1)) / _rms(steady, axis=0)
    assert np.all(spread > 0.005) and np.all(spread < 0.015), spread
    first = level3.y_raw[0, :PERIOD]
    transient = _rms(first - steady, axis=0) / _rms(steady, axis=0)
    assert np.all(transient > 2.5 * spread), (transient, spread)
    u = level3.X[0, :, 0].reshape(8, PERIOD)
    assert _rms(u - u.mean(axis=0)) / _rms(u) < 0.002


def test_sweep_layout(f16_dir):
    d = load_f16(f16_dir, kind="sinesweep", level=3)
    assert d.X_raw.shape == (1, 108477, 1) and d.y_raw.shape == (1, 108477, 3)
    assert d.X.shape == (1, 107283, 1) and d.y.shape == (1, 107283, 3)
    assert np.all(d.X_raw[0, 107283:] == 0) and np.all(d.y_raw[0, 107283:] == 0)
    assert d.period is None and d.lines is None and d.fs == 400.0
    assert d.validation_level == 2 and d.X_val.shape == (1, 107581, 1)
    # the longer level-4 test sweep is not a whole number of multisine periods
    d4 = load_f16(f16_dir, kind="sinesweep", level=4)
    assert d4.X.shape == (1, 115968, 1) and d4.validation_level is None and d4.X_val is None


def test_validation_level_argument(f16_dir):
    d = load_f16(f16_dir, level=5, validation_level=6)
    assert d.validation_level == 6 and _rms(d.X_val) == pytest.approx(85.7, rel=0.01)
    assert load_f16(f16_dir, level=7, validation_level=None).X_val is None
    with pytest.raises(ValueError, match="validation_level"):
        load_f16(f16_dir, level=3, validation_level=9)


def test_excited_lines_leave_out_mains_hum(f16_dir, level3):
    """The full multisine excites bins 41-307 (2-15 Hz). Within -60 dB of
    the strongest line the measured force also has mains hum (bins 1024,
    3071, 3072) and leakage below 2 Hz, with 4e-6 of its power: they are
    not excited lines, at every level."""
    lines = np.arange(41, 308)
    np.testing.assert_array_equal(level3.lines, lines)
    for level in (1, 7):
        np.testing.assert_array_equal(load_f16(f16_dir, level=level, validation_level=None).lines, lines)
    from sklearn_pnlss import BLAEstimator

    bla = BLAEstimator(2, period=PERIOD, refine=False).fit(level3.X, level3.y)
    np.testing.assert_array_equal(bla.lines_, lines)


def _relative_errors(bla, X, y):
    band = bla.frf_
    frf = np.linalg.norm(bla.frf_model_ - band) / np.linalg.norm(band)
    sim = _rms(bla.predict(X) - y, axis=(0, 1)) / _rms(y, axis=(0, 1))
    return frf, sim


def test_bla_fits_the_measured_frf(level3):
    """Six states on the level-3 multisine: the model FRF within 18 % of the
    nonparametric BLA and the training data simulated within 19 % per
    output (measured 17.3 %; 18.5, 17.7, 17.3 %). Before the fix of the
    subspace fit: 86 % and 64-89 %."""
    from sklearn_pnlss import BLAEstimator

    bla = BLAEstimator(6, period=PERIOD, fs=400.0).fit(level3.X, level3.y)
    frf, sim = _relative_errors(bla, level3.X, level3.y)
    assert frf < 0.18 and np.all(sim < 0.19), (frf, sim)
    assert np.max(np.abs(np.linalg.eigvals(bla.A_))) < np.exp(-1 / PERIOD) + 1e-12


@pytest.mark.slow
def test_bla_improves_with_the_order(level3):
    """n = 6, 10, 16, 20 on the level-3 multisine (three outputs): relative
    FRF error 17.3, 12.2, 6.6, 6.2 % (before the fix: 86, 79, 29, 29 % with
    the mains hum among the lines, 22, 71, 57, 78 % without), simulation
    error of the training data per output 5.4-7.1 % at n = 20 (before: 22-29
    %). The rest of the misfit changes from line to line: the stochastic
    nonlinear distortion of one realisation, which no linear model follows.
    On the level-2 test multisine the error is 30-43 %, that of the level-3
    nonparametric BLA itself applied to it (29, 40, 41 %): the structure's
    linearisation changes with the level."""
    from sklearn_pnlss import BLAEstimator

    frf_errors = []
    for n, frf_max, sim_max in ((6, 0.18, 0.19), (10, 0.13, 0.16), (16, 0.07, 0.075), (20, 0.065, 0.075)):
        bla = BLAEstimator(n, period=PERIOD, fs=400.0).fit(level3.X, level3.y)
        frf, sim = _relative_errors(bla, level3.X, level3.y)
        assert frf < frf_max and np.all(sim < sim_max), (n, frf, sim)
        frf_errors.append(frf)
    assert np.all(np.diff(frf_errors) < 0), frf_errors
    _, val = _relative_errors(bla, level3.X_val, level3.y_val)
    assert np.all(val < 0.45), val


def test_bla_of_the_four_levels_is_continuous_in_the_data(f16_dir):
    """18 states on the four estimation levels together (the benchmark
    protocol's linear start): a relative change of 1e-14 in the force (a
    rounding difference between machines) left the model's test error as
    it was (mean NRMSE over levels 2, 4, 6: 0.425 and 0.432), and neither
    model's gain outside the band is far above the largest measured at the
    lines (1.004 times it at most). Before the kept fit had to meet the
    refinement's constraints, the unchanged data kept a free fit with a
    21.7 Hz resonance 2.7 times above the measured gain (test NRMSE 0.57,
    the perturbed data 0.43), from which the decoupled model tested 0.246
    against 0.189."""
    from sklearn_pnlss import BLAEstimator
    from sklearn_pnlss.statespace.linear import frequency_response

    train = [load_f16(f16_dir, level=lv, validation_level=None) for lv in (1, 3, 5, 7)]
    tests = [load_f16(f16_dir, level=lv, validation_level=None) for lv in (2, 4, 6)]
    X, y = np.concatenate([d.X for d in train]), np.concatenate([d.y for d in train])
    errors = []
    for eps in (0.0, 1e-14):
        Xp = X * (1 + eps * np.random.default_rng(0).standard_normal(X.shape))
        bla = BLAEstimator(18, period=PERIOD, fs=400.0).fit(Xp, y)
        errors.append(np.mean([_rms(bla.predict(d.X) - d.y, axis=(0, 1)) / _rms(d.y, axis=(0, 1)) for d in tests]))
        outside = np.setdiff1d(np.arange(PERIOD // 2 + 1), bla.lines_)
        gain = np.abs(frequency_response(bla.A_, bla.B_, bla.C_, bla.D_, np.exp(2j * np.pi * outside / PERIOD)))
        assert np.all(gain.max(axis=0) < 1.5 * np.abs(bla.frf_).max(axis=0)), eps
    assert abs(errors[0] - errors[1]) < 0.02 and max(errors) < 0.45, errors
