"""The fitting engine (statespace/fitting.py, statespace/degree_growth.py)
on its own, without the estimators: Levenberg-Marquardt recovers a known
model, validation keeps the best iterate, the trusted range is the range the
training simulation covers, degrees grow stage by stage, and a start
stable at rest stays so when asked (else the estimators say it is not)."""
import warnings

import numpy as np
import pytest

from sklearn_pnlss.signals import multisine
from sklearn_pnlss.statespace.degree_growth import degree_stages, optimise_growing_degrees, with_degrees
from sklearn_pnlss.statespace.fitting import FitSettings, optimise, simulation_objectives, trusted_model
from sklearn_pnlss.statespace.model_base import DivergenceError
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel
from sklearn_pnlss.statespace.scaled import ScaledModel

PERIOD = 128


def _truth():
    """Two states, a cubic in the first state: x1(t+1) gets -0.3 x1^3."""
    ex = monomial_exponents(3, (2, 3))
    E = np.zeros((2, len(ex)))
    E[0, np.flatnonzero((ex == [3, 0, 0]).all(axis=1))[0]] = -0.3
    return PNLSSModel(
        A=np.array([[0.6, 0.3], [-0.3, 0.6]]), B=np.array([[1.0], [0.5]]), C=np.array([[1.0, 0.0]]),
        D=np.zeros((1, 1)), E=E, F=np.zeros((1, 0)), exE=ex, exF=np.zeros((0, 3), dtype=np.int64),
    )


def _signals(seed, n_realizations=2, rms=0.5):
    X, _ = multisine(PERIOD, fs=1.0, f_band=(0.01, 0.4), rms=rms, n_periods=2,
                     n_realizations=n_realizations, random_state=seed)
    truth = _truth()
    return list(X), [truth.simulate_signal(U, PERIOD) for U in X]


def _unit(model):
    return ScaledModel(model, np.ones(1), np.ones(1), np.ones(model.n_states))


def _linear_start():
    truth = _truth()
    return _unit(PNLSSModel(A=truth.A.copy(), B=truth.B.copy(), C=truth.C.copy(), D=truth.D.copy(),
                            E=np.zeros_like(truth.E), F=truth.F.copy(), exE=truth.exE, exF=truth.exF))


def _rms_db(model, X, y):
    err = np.concatenate([model.simulate(U, PERIOD) - Y for U, Y in zip(X, y)])
    return 20 * np.log10(np.sqrt(np.mean(err**2)))


def test_optimise_recovers_a_known_model():
    X, y = _signals(0)
    settings = FitSettings(period=PERIOD, max_iter=100, extrapolation="polynomial")
    start = _linear_start()
    objectives = simulation_objectives(start, X, y, settings)
    assert len(objectives) == 1
    fit = optimise(start, objectives, settings)
    X_new, y_new = _signals(5)
    # The linear start is 10 dB off; the fitted model is the truth up to
    # numerical precision (noise-free data), on new signals too (measured:
    # -10.5 dB, then -268.0 dB after 68 iterations, when LM stops; -257.1 dB
    # after 60).
    assert _rms_db(start, X_new, y_new) > -15
    assert _rms_db(fit.model, X_new, y_new) < -200
    assert fit.cost_history[-1] < 1e-20 * fit.cost_history[0]
    assert fit.best_iteration == fit.n_iter < 100
    assert fit.validation_history is None and np.isnan(fit.validation_error)


def test_validation_keeps_the_best_iterate():
    X, y = _signals(0)
    X_val, y_val = _signals(3, n_realizations=1)
    settings = FitSettings(period=PERIOD, max_iter=8, extrapolation="polynomial")
    start = _linear_start()
    fit = optimise(start, simulation_objectives(start, X, y, settings), settings, validation=(X_val, y_val))
    history = fit.validation_history
    assert history.shape == (fit.n_iter + 1,)
    assert fit.best_iteration == int(np.argmin(history))
    assert fit.validation_error == history.min()
    # The kept model's validation error is the one recorded for it.
    assert _rms_db(fit.model, X_val, y_val) == pytest.approx(fit.validation_error, abs=1e-6)


def test_trusted_range_is_the_training_range_widened_by_the_margin():
    X, y = _signals(0)
    truth = _unit(_truth())
    settings = FitSettings(period=PERIOD, range_margin=0.1)
    segments = simulation_objectives(truth, X, y, settings)[0].segments
    held = trusted_model(truth.normalised, segments, settings)
    states = np.vstack([truth.normalised.simulate_states(seg.U) for seg in segments])
    lo, hi = states.min(axis=0), states.max(axis=0)
    np.testing.assert_allclose(held.bounds[:2], np.column_stack([lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo)]))
    assert np.all(np.isinf(held.bounds[2]))  # the input is not bounded
    plain = trusted_model(truth.normalised, segments, FitSettings(period=PERIOD, extrapolation="polynomial"))
    assert np.all(np.isinf(plain.bounds))


def test_the_trusted_range_reuses_the_last_residual_simulations():
    X, y = _signals(0)
    truth = _unit(_truth())
    settings = FitSettings(period=PERIOD)
    objective = simulation_objectives(truth, X, y, settings)[0]
    model = truth.normalised
    other = model.with_theta(model.theta * 1.01)
    objective.residual(model)
    reused = objective.trajectory(model)
    assert np.array_equal(reused, model.segments_trajectory(objective.segments))
    # another model's trajectory is simulated anew, not taken from the cache
    assert np.array_equal(objective.trajectory(other), other.segments_trajectory(objective.segments))
    assert not np.array_equal(objective.trajectory(other), reused)
    assert np.array_equal(trusted_model(model, objective.segments, settings, objective).bounds,
                          trusted_model(model, objective.segments, settings).bounds)


def _self_exciting(seed):
    """Signals of ``_truth`` with its linear part 1 % unstable (negative
    damping at rest) and a cubic that damps it at the forced amplitude,
    and a linear start stable at rest."""
    truth = _truth()
    truth.A = 1.01 * np.array([[0.8, 0.6], [-0.6, 0.8]])
    truth.E[0, np.flatnonzero((truth.exE == [3, 0, 0]).all(axis=1))[0]] = -0.1
    X, _ = multisine(PERIOD, fs=1.0, f_band=(0.01, 0.4), rms=0.5, n_periods=2, n_realizations=2, random_state=seed)
    start = _unit(PNLSSModel(A=truth.A / 1.01 * 0.95, B=truth.B.copy(), C=truth.C.copy(), D=truth.D.copy(),
                             E=np.zeros_like(truth.E), F=truth.F.copy(), exE=truth.exE, exF=truth.exF))
    return truth, list(X), [truth.simulate_signal(U, PERIOD) for U in X], start


def test_a_start_at_rest_stays_at_rest():
    truth, X, y, start = _self_exciting(0)
    assert not truth.stable_at_rest() and start.normalised.stable_at_rest()
    settings = FitSettings(period=PERIOD, max_iter=100, extrapolation="polynomial", stable_at_rest=True)
    fit = optimise(start, simulation_objectives(start, X, y, settings), settings)
    # every step that would make the model ring by itself is refused; the
    # fit still gets close (measured: the cost falls from 204 to 0.60)
    assert fit.model.normalised.stable_at_rest()
    assert fit.cost_history[-1] < 1e-2 * fit.cost_history[0]
    # without the check the fit goes to the truth, unstable at rest
    settings = FitSettings(period=PERIOD, max_iter=100, extrapolation="polynomial")
    free = optimise(start, simulation_objectives(start, X, y, settings), settings)
    radius = np.abs(np.linalg.eigvals(free.model.normalised.state_matrix_at_rest()))
    np.testing.assert_allclose(radius, 1.01, atol=1e-6)


def test_the_estimators_keep_or_report_a_model_unstable_at_rest():
    from sklearn_pnlss import PNLSSRegressor

    _, X, y, _ = _self_exciting(0)
    settings = dict(degrees=(3,), variables="states", period=PERIOD, extrapolation="polynomial", max_iter=100)
    with pytest.warns(UserWarning, match="unstable at rest .*radius 1.01.*stable_at_rest=True"):
        free = PNLSSRegressor(2, **settings).fit(np.stack(X), np.stack(y))
    assert not free.model_.normalised.stable_at_rest()
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        kept = PNLSSRegressor(2, stable_at_rest=True, **settings).fit(np.stack(X), np.stack(y))
    assert kept.model_.normalised.stable_at_rest()


def test_a_diverging_start_is_refused():
    X, y = _signals(0)
    unstable = _truth()
    unstable.A = 1.2 * np.eye(2)
    settings = FitSettings(period=PERIOD)
    start = _unit(unstable)
    with pytest.raises(DivergenceError, match="start model diverges"):
        optimise(start, simulation_objectives(start, X, y, settings), settings)


def test_frequency_weighting_stages_and_errors():
    X, y = _signals(0)
    start = _linear_start()
    assert len(simulation_objectives(start, X, y, FitSettings(period=PERIOD, weighting="band"))) == 1
    # Noise weighting: unweighted first, then weighted (two stages).
    noisy = [Y + 1e-3 * np.random.default_rng(i).standard_normal(Y.shape) for i, Y in enumerate(y)]
    assert len(simulation_objectives(start, X, noisy, FitSettings(period=PERIOD, weighting="noise"))) == 2
    with pytest.raises(ValueError, match="band must be"):
        simulation_objectives(start, X, y, FitSettings(period=PERIOD, weighting="band", band=(0, PERIOD)))
    with pytest.raises(ValueError, match="set period"):
        simulation_objectives(start, X, y, FitSettings(period=None, weighting="band"))


def test_degree_stages():
    assert degree_stages([2, 3, 5, 7], "auto") == [(2, 3), (2, 3, 5), (2, 3, 5, 7)]
    assert degree_stages([2, 3, 5, 7], True) == [(2,), (2, 3), (2, 3, 5), (2, 3, 5, 7)]
    assert degree_stages([5, 7], "auto") == [(5,), (5, 7)]
    assert degree_stages([2, 3, 5], False) == [(2, 3, 5)]


def test_growing_degrees_carries_each_stage_over():
    X, y = _signals(0)
    X_val, y_val = _signals(3, n_realizations=1)
    settings = FitSettings(period=PERIOD, max_iter=40, extrapolation="polynomial")
    start = _linear_start()
    objectives = simulation_objectives(start, X, y, settings)
    fit = optimise_growing_degrees(start, objectives, settings, [(2,), (2, 3)], (X_val, y_val))
    # Stage 1 runs at most max_iter // 2, stage 2 at most max_iter; the
    # validation history runs on across both (each stage's start once).
    assert fit.n_iter <= 20 + 40
    assert fit.validation_history.shape == (fit.n_iter + 1,)
    assert fit.best_iteration == int(np.argmin(fit.validation_history))
    assert _rms_db(fit.model, X_val, y_val) < -105  # measured -109.8 dB
    # with_degrees: the degree-2 columns of the first stage carry over.
    low = with_degrees(start.normalised, (2,), None)
    low.E[:] = 1.0
    grown = with_degrees(start.normalised, (2, 3), low)
    degree = grown.exE.sum(axis=1)
    assert np.all(grown.E[:, degree == 2] == 1.0) and np.all(grown.E[:, degree == 3] == 0.0)


def test_iteration_listener_hears_every_iteration():
    from sklearn_pnlss.statespace.fitting import iteration_listener

    X, y = _signals(0)
    settings = FitSettings(period=PERIOD, max_iter=5, tol=0.0, extrapolation="polynomial")
    start = _linear_start()
    heard = []
    with iteration_listener(lambda it, cost_db: heard.append((it, cost_db))):
        fit = optimise(start, simulation_objectives(start, X, y, settings), settings)
    assert [it for it, _ in heard] == list(range(fit.n_iter + 1))
    # The costs heard are the cost history's, in dB of the rms error.
    n_res = sum(Y.size for Y in y) // 2  # periods averaged
    np.testing.assert_allclose([c for _, c in heard], 10 * np.log10(fit.cost_history / n_res), rtol=1e-12)
    optimise(start, simulation_objectives(start, X, y, settings), settings)
    assert len(heard) == fit.n_iter + 1  # nothing heard outside the block
