import numpy as np
import pytest

from sklearn_pnlss.signals import (
    bouc_wen_sweep,
    linear_chirp,
    multisine,
    multisine_lines,
    swept_sine,
)


def _amplitudes(x):
    return np.abs(np.fft.rfft(x)) * 2 / x.size


@pytest.mark.parametrize("n_inputs", [1, 2])
def test_multisine_shape_rms_and_flat_spectrum(n_inputs):
    X, lines = multisine(1024, fs=750.0, f_band=(5.0, 150.0), rms=50.0, n_periods=3,
                         n_realizations=2, n_inputs=n_inputs, random_state=0)
    assert X.shape == (2, 3 * 1024, n_inputs)
    k = np.arange(1024 // 2 + 1)
    f = k * 750.0 / 1024
    np.testing.assert_array_equal(lines, k[(f >= 5.0) & (f <= 150.0) & (k >= 1)])
    for r in range(2):
        for i in range(n_inputs):
            x = X[r, :, i]
            assert np.sqrt(np.mean(x**2)) == pytest.approx(50.0, rel=1e-12)
            np.testing.assert_allclose(x[:1024], x[2048:], atol=1e-12)
            amp = _amplitudes(x[:1024])
            np.testing.assert_allclose(amp[lines], amp[lines][0], rtol=1e-9)
            others = np.setdiff1d(k, lines)
            assert np.max(amp[others]) < 1e-10 * amp[lines][0]
    # realisations and inputs get independent phases
    assert not np.allclose(X[0], X[1])
    if n_inputs == 2:
        assert not np.allclose(X[0, :, 0], X[0, :, 1])


def test_multisine_reproducible():
    a, _ = multisine(256, random_state=3, n_realizations=2)
    b, _ = multisine(256, random_state=3, n_realizations=2)
    c, _ = multisine(256, random_state=4, n_realizations=2)
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, c)
    rng = np.random.RandomState(0)
    d1, _ = multisine(256, random_state=rng)
    d2, _ = multisine(256, random_state=rng)
    assert not np.allclose(d1, d2)


def test_odd_and_random_odd_lines():
    full = multisine_lines(200, fs=200.0, f_band=(1.0, 40.0))
    np.testing.assert_array_equal(full, np.arange(1, 41))
    odd = multisine_lines(200, fs=200.0, f_band=(1.0, 40.0), kind="odd")
    np.testing.assert_array_equal(odd, np.arange(1, 41, 2))
    ro = multisine_lines(200, fs=200.0, f_band=(1.0, 40.0), kind="random_odd",
                         group_size=4, random_state=0)
    # 20 odd lines in 5 groups of 4: one detection line removed per group
    assert ro.size == 15
    assert np.all(ro % 2 == 1)
    for g in range(5):
        group = odd[4 * g: 4 * g + 4]
        assert np.isin(group, ro).sum() == 3
    X, lines = multisine(200, fs=200.0, f_band=(1.0, 40.0), kind="random_odd",
                         group_size=4, n_realizations=3, random_state=0)
    amp = _amplitudes(X[2, :, 0])
    np.testing.assert_array_equal(np.flatnonzero(amp > 1e-8 * amp.max()), lines)


def test_random_odd_keeps_incomplete_trailing_group():
    ro = multisine_lines(100, fs=100.0, f_band=(1.0, 9.0), kind="random_odd",
                         group_size=3, random_state=1)
    # odd lines 1..9: one group of 3 (one dropped) + 2 kept
    assert ro.size == 4
    assert {7, 9} <= set(ro.tolist())


def test_multisine_nyquist_line_is_flat():
    X, lines = multisine(16, fs=16.0, f_band=(1.0, 8.0), random_state=0,
                         n_realizations=4)
    assert lines[-1] == 8
    for x in X[:, :, 0]:
        amp = np.abs(np.fft.rfft(x)) / x.size * 2
        amp[-1] /= 2  # the Nyquist bin counts once
        np.testing.assert_allclose(amp[1:], amp[1], rtol=1e-10)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(f_band=(0.0, 100.0)), "f_band"),
        (dict(f_band=(5.0, 400.0)), "f_band"),
        (dict(f_band=(100.0, 50.0)), "f_band"),
        (dict(f_band=5.0), "f_band"),
        (dict(f_band=(5.01, 5.02)), "no 'full' DFT line"),
        (dict(rms=0.0), "rms"),
        (dict(rms=-1.0), "rms"),
        (dict(kind="even"), "kind"),
        (dict(n_periods=0), "n_periods"),
        (dict(n_realizations=1.5), "n_realizations"),
        (dict(n_inputs=0), "n_inputs"),
        (dict(kind="random_odd", group_size=1), "group_size"),
        (dict(fs=-1.0), "fs"),
    ],
)
def test_multisine_errors(kwargs, match):
    with pytest.raises(ValueError, match=match):
        multisine(1024, **kwargs)


def test_multisine_errors_n_samples():
    with pytest.raises(ValueError, match="n_samples"):
        multisine(1)


def test_bouc_wen_sweep_formula():
    u = bouc_wen_sweep()
    assert u.shape == (153000,)
    t = np.arange(153000) / 750.0
    # large phases (~4.5e4 rad) leave ~1e-9 of round-off, as in the official file
    np.testing.assert_allclose(u, 40 * np.sin(2 * np.pi * (18 * t + t**2 / 12)),
                               atol=1e-8)
    fine = bouc_wen_sweep(1000, oversampling=20)
    assert fine.shape == (20000,)
    np.testing.assert_array_equal(fine[::20], bouc_wen_sweep(1000))
    tf = np.arange(20000) / 15000.0
    np.testing.assert_allclose(
        fine, linear_chirp(tf, f_start=18.0, rate=1 / 6, amplitude=40.0), atol=1e-9
    )


def test_swept_sine_matches_benchmark_sweep():
    u = swept_sine(153000, fs=750.0, f_start=18.0, f_stop=52.0, amplitude=40.0)
    np.testing.assert_allclose(u, bouc_wen_sweep(), atol=1e-9)
    uf = swept_sine(1500, fs=750.0, f_start=10.0, f_stop=20.0, oversampling=4)
    np.testing.assert_allclose(uf[::4], swept_sine(1500, fs=750.0, f_start=10.0,
                                                   f_stop=20.0))


def test_swept_sine_instantaneous_frequency():
    fs, n = 1000.0, 20000
    u = swept_sine(n, fs=fs, f_start=5.0, f_stop=25.0)
    # zero crossings in the last second ~ 2 * f(t) ~ 2 * 24.5 per second
    tail = u[-1000:]
    crossings = np.sum(np.signbit(tail[1:]) != np.signbit(tail[:-1]))
    assert abs(crossings - 49) <= 1


def test_swept_sine_errors():
    with pytest.raises(ValueError, match="fs"):
        swept_sine(100, fs=0.0, f_start=1.0, f_stop=2.0)
    with pytest.raises(ValueError, match="n_samples"):
        swept_sine(0, fs=10.0, f_start=1.0, f_stop=2.0)
    with pytest.raises(ValueError, match="oversampling"):
        bouc_wen_sweep(100, oversampling=0)
