"""The PNLSS fit's machinery: the LM step from the normal equations, period
averaging, time and frequency weighting, validation-based iterate selection,
multiple inputs and outputs."""
import numpy as np
import pytest

from sklearn_pnlss import BLAEstimator, PNLSSRegressor
from sklearn_pnlss.statespace.degree_growth import with_degrees
from sklearn_pnlss.signals import multisine
from sklearn_pnlss.statespace.levenberg_marquardt import lm_step_basis
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.objective import SimulationError, weigh
from sklearn_pnlss.statespace.pnlss import PNLSSModel, Segment
from sklearn_pnlss.utils.handover import attach_stage

N = 256


def _truth(rng, m=1, p=1, n=3, scale_E=0.02):
    """A stable PNLSS system: small random quadratic and cubic terms plus a
    hardening cubic on each state (random cubics alone tend to escape)."""
    exE = monomial_exponents(n + m, (2, 3))
    E = scale_E * rng.standard_normal((n, len(exE)))
    for i in range(n):
        E[i, np.flatnonzero(exE[:, i] == 3)] = -0.1
    return PNLSSModel(
        A=np.diag([0.85, 0.6, 0.3])[:n, :n] + 0.02 * rng.standard_normal((n, n)),
        B=0.3 * rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=0.1 * rng.standard_normal((p, m)),
        E=E, F=np.zeros((p, 0)),
        exE=exE, exF=np.zeros((0, n + m), dtype=np.int64),
    )


def _data(truth, m=1, n_periods=2, n_realizations=2, seed=2, noise=0.0, rms=0.5):
    rng = np.random.default_rng(seed)
    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=rms, n_periods=n_periods,
                     n_realizations=n_realizations, n_inputs=m, random_state=seed)
    y = np.stack([truth.simulate_signal(x, period=N) for x in X])
    return X, y + noise * y.std() * rng.standard_normal(y.shape)


def two_levels(n_periods, n_realizations):
    """``truth, X, y``: two levels of a campaign, a quiet one (rms 0.2) with
    0.2 % noise and a loud one (0.5) with 20 %."""
    rng = np.random.default_rng(21)
    truth = _truth(rng)
    Xq, yq = _data(truth, n_periods=n_periods, n_realizations=n_realizations, rms=0.2, seed=1)
    Xl, yl = _data(truth, n_periods=n_periods, n_realizations=n_realizations, rms=0.5, seed=6)
    yq = yq + 0.002 * yq.std() * rng.standard_normal(yq.shape)
    yl = yl + 0.2 * yl.std() * rng.standard_normal(yl.shape)
    return truth, np.concatenate([Xq, Xl]), np.concatenate([yq, yl])


def test_step_basis_equals_the_svd_of_the_scaled_jacobian():
    rng = np.random.default_rng(0)
    J = rng.standard_normal((500, 8)) * np.logspace(0, 4, 8)
    J[:, 7] = J[:, 0] + J[:, 1]  # one exact null direction, to be dropped
    scale, S, V = lm_step_basis(J.T @ J, n_drop=1)
    _, S_svd, Vt = np.linalg.svd(J / scale, full_matrices=False)
    np.testing.assert_allclose(S, S_svd[:7], rtol=1e-9)
    np.testing.assert_allclose(np.abs(V.T @ Vt[:7].T), np.eye(7), atol=1e-8)


def test_frequency_weighting_with_unit_weights_is_parseval_and_jacobian_is_consistent():
    rng = np.random.default_rng(1)
    model = _truth(rng)
    U = 0.3 * rng.standard_normal((3 * N + 20, 1))
    Y = rng.standard_normal((3 * N, 1))
    plain = SimulationError([Segment(U, Y, 20)])
    freq = SimulationError([Segment(U, Y, 20, freq_weight=np.ones((N // 2 + 1, 1)), period=N)])
    e_t, e_f = plain.residual(model), freq.residual(model)
    assert np.isclose(e_t @ e_t, e_f @ e_f, rtol=1e-12)
    # A band weight: the gradient J^T e matches finite differences of the cost.
    w = np.zeros((N // 2 + 1, 1))
    w[10:40] = rng.uniform(0.5, 2.0, (30, 1))
    band = SimulationError([Segment(U, Y, 20, freq_weight=w, period=N)])
    _, g = band.normal_equations(model)
    theta = model.theta
    for q in rng.choice(theta.size, 6, replace=False):
        d = np.zeros_like(theta)
        d[q] = 1e-6
        cost = [np.sum(band.residual(model.with_theta(theta + s * d)) ** 2) for s in (1, -1)]
        assert np.isclose((cost[0] - cost[1]) / 4e-6, g[q], rtol=1e-5, atol=1e-8 * np.abs(g).max())


def test_time_weights_scale_the_squared_error():
    R = np.arange(12.0).reshape(6, 2, 1)
    w = np.linspace(0, 1, 12).reshape(6, 2)
    out = weigh(Segment(None, None, 0, time_weight=w), R)
    np.testing.assert_allclose(out[:, 0] ** 2, (w * R[:, :, 0] ** 2).ravel())
    # A single-precision Jacobian stays single (its Gram matrix runs at the
    # single-precision rate).
    assert weigh(Segment(None, None, 0, time_weight=w), R.astype(np.float32)).dtype == np.float32


def test_period_averaging_keeps_the_optimum():
    truth = _truth(np.random.default_rng(3))
    X, y = _data(truth, n_periods=3, noise=0.01)
    fits = [PNLSSRegressor(3, period=N, max_iter=15, average_periods=a).fit(X, y) for a in (True, False)]
    yp = [f.predict(X) for f in fits]
    assert np.sqrt(np.mean((yp[0] - yp[1]) ** 2)) < 1e-3 * y.std()
    # The cost of the averaged fit is lower by about the number of periods
    # (the noise power of the average).
    ratio = fits[1].cost_history_[0] / fits[0].cost_history_[0]
    assert 2.0 < ratio < 3.5


def test_noise_weighting_beats_unweighted_under_coloured_noise():
    """Strong noise in part of the band: weighting by its inverse variance
    gets closer to the true system than treating all bins alike. Measured:
    -81 dB weighted, -57 dB unweighted. (Fits of this noisy record often
    leave their stable range on the validation multisine, with or without
    weighting: the system and level are chosen where neither does.)"""
    rng = np.random.default_rng(3)
    truth = _truth(rng)
    X, y_clean = _data(truth, n_periods=4, n_realizations=2, rms=0.3)
    noise = rng.standard_normal(y_clean.shape)
    spec = np.fft.rfft(noise, axis=1)
    k = np.fft.rfftfreq(noise.shape[1])
    spec *= np.where((k > 0.2) & (k < 0.3), 30.0, 0.3)[None, :, None]
    y = y_clean + 0.01 * y_clean.std() * np.fft.irfft(spec, n=noise.shape[1], axis=1)
    X_val, y_val = _data(truth, n_periods=1, n_realizations=1, seed=9, rms=0.3)
    errs = {}
    for weighting in (None, "noise"):
        model = PNLSSRegressor(3, period=N, weighting=weighting, max_iter=30).fit(X, y)
        errs[weighting] = -model.score(X_val, y_val)
    assert errs["noise"] < errs[None] - 6  # at least 6 dB closer to the truth


def test_noise_weighting_weighs_each_level_by_its_own_noise(monkeypatch):
    """Two levels of a campaign, the quiet one nearly noiseless (0.2 % of
    its rms), the loud one noisy (20 %): weighted by each record's own noise
    the quiet level counts as its noise deserves. Measured on 20 validation
    multisines between the levels: -58.9 dB, against -47.4 dB with each
    level relative to its power and -47.4 dB with the noise pooled over
    both records (the loud one's noise then weighs the quiet one). Each
    level has two realisations of eight periods: with one of four, every
    fit ran away on new realisations of the loud level and was taken back
    to its first iterates (-41.8 dB for all three)."""
    truth, X, y = two_levels(n_periods=8, n_realizations=2)
    X_val, y_val = _data(truth, n_periods=1, n_realizations=20, seed=10, rms=0.35)

    def error(weighting):
        return -PNLSSRegressor(3, period=N, weighting=weighting, max_iter=30, random_state=0).fit(
            X, y).score(X_val, y_val)

    own, relative = error("noise"), error("relative")
    from sklearn_pnlss.frequency.noise import periodic_noise_variance
    monkeypatch.setattr("sklearn_pnlss.statespace.fitting.signal_noise_variances",
                        lambda yn, period: [periodic_noise_variance(yn, period)] * len(yn))
    pooled = error("noise")
    assert own < -55 and own < relative - 8 and own < pooled - 8, (own, relative, pooled)


def test_validation_keeps_the_best_iterate():
    truth = _truth(np.random.default_rng(5))
    X, y = _data(truth, noise=0.05)
    X_val, y_val = _data(truth, n_periods=1, n_realizations=1, seed=7)
    model = PNLSSRegressor(3, period=N, max_iter=20).fit(X, y, X_val=X_val, y_val=y_val)
    hist = model.validation_history_
    assert hist.shape == (model.n_iter_ + 1,)
    assert model.best_iteration_ == int(np.argmin(hist))
    assert np.isclose(-model.score(X_val, y_val), hist.min(), atol=1e-6)


def test_time_weight_and_frequency_weighting_are_exclusive():
    truth = _truth(np.random.default_rng(6))
    X, y = _data(truth)
    with pytest.raises(ValueError, match="time_weight"):
        PNLSSRegressor(3, period=N, weighting="band", max_iter=1).fit(X, y, time_weight=np.ones(y.shape))
    # Without the channel axis: named, with the fix.
    with pytest.raises(ValueError, match=r"time_weight\[\.\.\., None\]"):
        PNLSSRegressor(3, period=N, max_iter=1).fit(X, y, time_weight=np.ones(y.shape[:2]))
    with pytest.raises(ValueError, match="layout of y"):
        PNLSSRegressor(3, period=N, max_iter=1).fit(X, y, time_weight=np.ones((y.shape[0] - 1,) + y.shape[1:]))
    with pytest.raises(ValueError, match="X_val and y_val"):
        PNLSSRegressor(3, period=N, max_iter=1).fit(X, y, X_val=X)
    with pytest.raises(ValueError, match="band must be"):
        PNLSSRegressor(3, period=N, weighting="band", band=(5, N), max_iter=1).fit(X, y)
    with pytest.raises(ValueError, match="set period"):
        PNLSSRegressor(3, weighting="noise", max_iter=1).fit(X, y)


def test_zero_time_weight_ignores_corrupted_samples():
    truth = _truth(np.random.default_rng(8))
    X, y = _data(truth)
    y_bad = y.copy()
    y_bad[0, 100:140] += 5 * y.std()  # a burst of corrupted samples
    w = np.ones(y.shape)
    w[0, 100:140] = 0.0
    X_val, y_val = _data(truth, n_periods=1, n_realizations=1, seed=7)
    kw = dict(period=N, max_iter=30, average_periods=False)
    err_w = -PNLSSRegressor(3, **kw).fit(X, y_bad, time_weight=w).score(X_val, y_val)
    err_u = -PNLSSRegressor(3, **kw).fit(X, y_bad).score(X_val, y_val)
    assert err_w < err_u - 10


def test_two_inputs_two_outputs():
    """MIMO: a 2-input, 2-output PNLSS system is recovered far below the
    output level from noiseless data."""
    rng = np.random.default_rng(10)
    truth = _truth(rng, m=2, p=2)
    X, y = _data(truth, m=2, n_periods=2, n_realizations=4, rms=0.2)
    model = PNLSSRegressor(3, period=N, max_iter=60).fit(X, y)
    assert model.n_outputs_ == 2 and model.B_.shape == (3, 2) and model.C_.shape == (2, 3)
    X_val, y_val = _data(truth, m=2, n_periods=1, n_realizations=2, seed=11, rms=0.2)
    # The linear model is 26 dB below the output, the PNLSS model 60 dB.
    assert -model.linear_model_.score(X_val, y_val) > 20 * np.log10(y_val.std()) - 30
    assert -model.score(X_val, y_val) < 20 * np.log10(y_val.std()) - 60
    assert model.n_nonlinear_params_ == 3 * len(monomial_exponents(5, (2, 3)))


def test_divergent_trial_steps_are_rejected_never_returned():
    """A residual that 'diverges' (None) beyond a wall: LM raises lambda
    until its steps stay inside and never returns a point beyond it."""
    from sklearn_pnlss.statespace.levenberg_marquardt import levenberg_marquardt

    target = np.array([3.0, -2.0])  # the unconstrained optimum lies beyond the wall at |theta| = 1.5
    visited = []

    def residual(theta):
        visited.append(theta.copy())
        if np.any(np.abs(theta) > 1.5):
            return None
        return np.concatenate([theta - target, 0.1 * theta**2])

    def normal_equations(theta):
        J = np.vstack([np.eye(2), np.diag(0.2 * theta)])
        e = residual(theta)
        return J.T @ J, J.T @ e

    result = levenberg_marquardt(residual, normal_equations, np.zeros(2), max_iter=50)
    assert np.all(np.abs(result.theta) <= 1.5) and np.all(np.isfinite(result.theta))
    assert any(np.any(np.abs(v) > 1.5) for v in visited)  # divergent trials did happen
    costs = [h[1] for h in result.history]
    assert np.all(np.diff(costs) <= 0)  # only improving steps accepted


def test_a_start_that_diverges_is_a_clear_error():
    """An unstable linear model handed over as the start: fit says so."""
    truth = _truth(np.random.default_rng(3))
    X, y = _data(truth)
    bla = BLAEstimator(3, period=N).fit(X, y)
    bla.A_ = 1.5 * np.eye(3)  # unstable
    with pytest.raises(ValueError, match="linear start diverges"):
        PNLSSRegressor(3, period=N, max_iter=3, n_transient=0).fit(attach_stage(X, bla), y)


def test_threads_over_signals_give_the_same_fit():
    truth = _truth(np.random.default_rng(3))
    X, y = _data(truth, n_realizations=4, noise=0.01)
    fits = [PNLSSRegressor(3, degrees=(2, 3), period=N, max_iter=8, n_jobs=n_jobs, random_state=0).fit(X, y)
            for n_jobs in (None, 2)]
    # Equal to rounding: the threads run BLAS single-threaded, which sums in another order.
    np.testing.assert_allclose(fits[1].cost_history_, fits[0].cost_history_, rtol=1e-12)
    np.testing.assert_allclose(fits[1].E_, fits[0].E_, rtol=1e-8, atol=1e-12 * np.abs(fits[0].E_).max())
    assert fits[1].cost_history_[-1] < 0.9 * fits[1].cost_history_[0]  # it did fit


def test_grown_degrees_start_each_stage_where_the_previous_ended():
    rng = np.random.default_rng(4)
    full = _truth(rng)
    full.E[...] = 0.0
    low = with_degrees(full, (2,), None)
    low.E[...] = 0.05 * rng.standard_normal(low.E.shape)
    grown = with_degrees(full, (2, 3), low)
    assert grown.E.shape == full.E.shape
    U = 0.5 * rng.standard_normal((300, 1))
    # The added degree-3 terms start at zero: the same model, the same output.
    np.testing.assert_array_equal(grown.simulate_signal(U), low.simulate_signal(U))
    assert np.count_nonzero(grown.E) == low.E.size


def test_growing_degrees_chains_the_stages():
    truth = _truth(np.random.default_rng(5))
    truth.E[:, truth.exE.sum(axis=1) == 2] = 0.0  # odd, as degrees (3, 5) can follow
    X, y = _data(truth, noise=0.001, rms=1.0)
    X_val, y_val = _data(truth, n_periods=1, n_realizations=1, seed=7, rms=1.0)

    def stages(**params):
        return PNLSSRegressor(3, period=N, max_iter=0, **params).fit(X, y).degree_stages_

    assert stages(degrees=(3, 2)) == [(2, 3)]
    assert stages(degrees=(2, 3, 5)) == [(2, 3), (2, 3, 5)]
    assert stages(degrees=(3, 5, 7)) == [(3,), (3, 5), (3, 5, 7)]
    assert stages(degrees=(2, 3), grow_degrees=True) == [(2,), (2, 3)]
    assert stages(degrees=(3, 5, 7), grow_degrees=False) == [(3, 5, 7)]
    direct = PNLSSRegressor(3, degrees=(3, 5), period=N, max_iter=20, grow_degrees=False).fit(X, y, X_val=X_val, y_val=y_val)
    grown = PNLSSRegressor(3, degrees=(3, 5), period=N, max_iter=20).fit(X, y, X_val=X_val, y_val=y_val)
    assert direct.degree_stages_ == [(3, 5)] and grown.degree_stages_ == [(3,), (3, 5)]
    hist = grown.validation_history_
    assert hist.shape == (grown.n_iter_ + 1,) and grown.n_iter_ > 20
    assert grown.best_iteration_ == int(np.argmin(hist))
    assert np.isclose(-grown.score(X_val, y_val), hist.min(), atol=1e-6)
    assert grown.n_params_ == direct.n_params_
    # Measured: the grown fit -38.8 dB, the direct one -38.1 dB, from -32.9 dB
    # (the late iterates of both run away on the validation input amplified
    # 1.2 times, though the truth does not even at 1.5: they are not kept).
    # With the toolbox's damping schedule the direct fit stalled at -36.3 dB;
    # Nielsen's closed most of that difference.
    assert np.isinf(hist).any() and np.isinf(direct.validation_history_).any()
    assert hist.min() < hist[0] - 5
    assert hist.min() < direct.validation_history_.min() - 0.3


def test_relative_weighting_fits_records_of_different_levels_alike():
    """A quiet and a loud record of a hardening system, fitted together by
    a linear model, which cannot match both: unweighted, the loud record's
    power decides, and the quiet one's NRMSE on new data is 0.27; with each
    record's error relative to its own power, 0.17 (the loud one moves from
    0.73 to 0.75: the mean NRMSE, what the benchmarks score, falls)."""
    truth = _truth(np.random.default_rng(3))
    Xq, yq = _data(truth, n_realizations=1, rms=0.05, seed=1)
    Xl, yl = _data(truth, n_realizations=1, rms=0.8, seed=2)
    X, y = np.concatenate([Xq, Xl]), np.concatenate([yq, yl])
    new = [_data(truth, n_realizations=1, rms=0.05, seed=5), _data(truth, n_realizations=1, rms=0.8, seed=6)]

    def nrmse(model):
        return np.array([np.sqrt(np.mean((yv - model.predict(Xv)) ** 2) / np.mean(yv**2)) for Xv, yv in new])

    plain, relative = (nrmse(PNLSSRegressor(3, degrees=(), period=N, max_iter=20, weighting=w).fit(X, y))
                       for w in (None, "relative"))
    assert relative[0] < 0.7 * plain[0]
    assert relative.mean() < plain.mean() - 0.02
    # One record (or records of one level): the same fit as unweighted.
    one = [PNLSSRegressor(3, degrees=(2,), period=N, max_iter=5, weighting=w, random_state=0)
           .fit(Xl, yl).predict(Xl)
           for w in (None, "relative")]
    np.testing.assert_allclose(one[0], one[1], rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="output 0 of training signal 1 is constant"):
        PNLSSRegressor(3, period=N, max_iter=1, weighting="relative").fit(X, np.concatenate([yq, 0 * yl]))
