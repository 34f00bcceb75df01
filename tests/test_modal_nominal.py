"""A structure's modes read off measured data (the nominal of a structure
that has only test data): a known chain recovered, and the F-16's modes."""
import numpy as np
import pytest
from scipy.linalg import eigh

from sklearn_pnlss.datasets import load_f16
from sklearn_pnlss.gap.modal_nominal import fit_modes, modal_nominal
from sklearn_pnlss.physics import Structure

POINTS = ["base", "middle", "tip"]
M = np.diag([3.0, 2.0, 1.0])
K = 5e4 * np.array([[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
C = 1e-4 * K + 0.5 * M
SENSORS = [(p, "acceleration") for p in POINTS]


def _chain_data(noise=0.0, seed=0):
    """Two periodic realisations of a multisine at the base, accelerations
    at the three masses, simulated at 20 times the data rate."""
    rng = np.random.default_rng(seed)
    n, fs = 4096, 200.0
    lines = np.arange(20, 1700, 4)  # 1-83 Hz
    X, Y = [], []
    for _ in range(2):
        spectrum = np.zeros(n // 2 + 1, complex)
        spectrum[lines] = np.exp(2j * np.pi * rng.random(lines.size))
        u = np.fft.irfft(spectrum, n) * np.sqrt(n)
        a = Structure(M, C, K, points=POINTS).simulate(u, fs=fs, inputs="base", sensors=SENSORS, periodic=True,
                                                       oversampling=20, decimation=(2, 2, 5))
        X.append(np.tile(u, 2)[:, None])
        Y.append(np.tile(a, (2, 1)) + noise * a.std(0) * rng.standard_normal((2 * n, 3)))
    return np.array(X), np.array(Y), fs


def test_a_chains_modes_and_mass_normalised_shapes_are_recovered():
    """Three masses in a chain, driven at the base: 'auto' finds the three
    modes, their frequencies and damping ratios, and the mode shapes at the
    three sensors, mass-normalised through the driving point, as the
    eigenproblem has them (to the integrator's discretisation)."""
    X, Y, fs = _chain_data()
    nominal = modal_nominal(X, Y, fs=fs, points=POINTS, driving_point="base", period=4096, f_band=(1.0, 80.0))
    fit = nominal.modal_fit_
    w2, phi = eigh(K, M)
    omega = np.sqrt(w2)
    assert fit.frequencies.size == 3
    np.testing.assert_allclose(fit.frequencies, omega / (2 * np.pi), rtol=2e-3)
    np.testing.assert_allclose(fit.damping_ratios, np.diag(phi.T @ C @ phi) / (2 * omega), rtol=2e-2)
    phi = phi * np.sign(phi[0])  # the driving point's shape is positive
    np.testing.assert_allclose(nominal.point_matrix[:, :3], phi, atol=5e-3 * np.abs(phi).max())
    assert fit.relative_error < 5e-3


def test_noise_leaves_the_modes_within_their_uncertainty():
    X, Y, fs = _chain_data(noise=0.02, seed=1)
    fit = modal_nominal(X, Y, fs=fs, points=POINTS, driving_point="base", period=4096,
                        f_band=(1.0, 80.0)).modal_fit_
    omega = np.sqrt(eigh(K, M, eigvals_only=True))
    assert fit.frequencies.size == 3
    np.testing.assert_allclose(fit.frequencies, omega / (2 * np.pi), rtol=3e-3)


def test_modes_the_data_cannot_tell_apart_are_refused():
    """Asked for more modes than the chain has, the fit puts two in one
    resonance or outside the band, and says so."""
    X, Y, fs = _chain_data()
    with pytest.raises(ValueError, match="fewer modes"):
        modal_nominal(X, Y, fs=fs, points=POINTS, driving_point="base", n_modes=5, period=4096,
                      f_band=(1.0, 80.0))


@pytest.mark.parametrize("kwargs, match", [
    (dict(driving_point="wing"), "driving_point must be one of"),
    (dict(n_modes=0), "n_modes must be a positive int"),
    (dict(points=["a", "b"]), "one column per point"),
])
def test_bad_arguments_say_what_to_fix(kwargs, match):
    X, Y, fs = _chain_data()
    args = dict(fs=fs, points=POINTS, driving_point="base", period=4096) | kwargs
    with pytest.raises(ValueError, match=match):
        modal_nominal(X, Y, **args)


def test_fit_modes_refuses_too_few_lines():
    with pytest.raises(ValueError, match="too few"):
        fit_modes(np.arange(1.0, 5.0), np.ones((4, 1)), 3, fs=100.0)


def test_the_f16s_modes_soften_and_damp_with_level(f16_dir):
    """The F-16 ground vibration test (real data), 2-15 Hz: the nominal read
    off the lowest level holds six modes and reproduces that level's
    accelerations (NRMSE at most 0.12 at each sensor in the band); from
    the lowest level to the highest every mode's frequency falls and all
    but one's damping rises (the bolted interface's friction and
    clearance), and the nominal's error on the next level up is four
    times its own level's at the wing and payload sensors."""
    points = ["drive", "wing", "payload"]
    sensors = [(p, "acceleration") for p in points]
    fits, data = {}, {}
    for level in (1, 2, 7):
        d = data[level] = load_f16(f16_dir, level=level, validation_level=None)
        if level != 2:
            fits[level] = modal_nominal(d.X, d.y, fs=400.0, points=points, driving_point="drive", period=8192,
                                        f_band=(2.0, 15.0))
    low, high = fits[1].modal_fit_, fits[7].modal_fit_
    assert low.frequencies.size == high.frequencies.size == 6
    assert np.all(high.frequencies < low.frequencies)
    assert np.sum(high.damping_ratios > low.damping_ratios) >= 5

    def band_nrmse(level):
        d = data[level]
        a = fits[1].simulate(d.X[0, :8192, 0], fs=400.0, inputs="drive", sensors=sensors, periodic=True)
        y = d.y[0].reshape(-1, 8192, 3).mean(0)
        A, Y = np.fft.rfft(a, axis=0), np.fft.rfft(y, axis=0)
        f = np.arange(A.shape[0]) * 400.0 / 8192
        band = (f >= 2.0) & (f <= 15.0)
        return np.sqrt(np.sum(np.abs(A[band] - Y[band]) ** 2, 0) / np.sum(np.abs(Y[band]) ** 2, 0))

    own, next_up = band_nrmse(1), band_nrmse(2)
    assert np.all(own < 0.12), own
    assert np.all(next_up[1:] > 4 * own[1:]), (own, next_up)
