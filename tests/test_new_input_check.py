"""The fitted model is checked on new realisations of its training inputs:
an iterate that runs away on them is not returned."""
import warnings
from dataclasses import replace
from unittest import mock

import numpy as np
import pytest

from sklearn_pnlss import PNLSSRegressor
from sklearn_pnlss.statespace.fitting import _sane_on_new_inputs
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.new_inputs import random_phase_inputs
from sklearn_pnlss.statespace.pnlss import PNLSSModel
from test_pnlss_fitting import N, _data, _truth, two_levels


def test_random_phase_inputs_keep_the_spectrum_and_the_peak():
    X, _ = _data(_truth(np.random.default_rng(0)), n_periods=2, n_realizations=2, rms=0.5, seed=3)
    new = random_phase_inputs(list(X), N, n_inputs=6, random_state=0)
    assert len(new) == 6 and all(U.shape == (N, 1) for U in new)
    for k, U in enumerate(new):
        reference = X[k % 2, :N]
        assert np.max(np.abs(U)) <= np.max(np.abs(reference)) + 1e-12
        # the spectrum up to one common scale (the peak's)
        R = np.abs(np.fft.rfft(reference[:, 0]))
        excited = R > 1e-8 * R.max()
        ratio = np.abs(np.fft.rfft(U[:, 0]))[excited] / R[excited]
        assert np.ptp(ratio) < 1e-9 and 0.6 < ratio[0] <= 1 + 1e-12
    assert not np.allclose(new[0], X[0, :N])
    assert random_phase_inputs([X[0, :N + 5]], N) == ()  # not whole periods: nothing to check
    assert random_phase_inputs(list(X), None) == ()


def test_a_model_that_runs_away_on_new_realisations_is_not_returned():
    """Unchecked, the last iterate ran away on 17 of 20 new realisations of
    the loud level (errors up to 16 dB above the output's unit scale, the
    validation level 0.35 on 4 of 20); checked, on none of them."""
    # one realisation of four periods per level: data a fit overfits
    truth, X, y = two_levels(n_periods=4, n_realizations=1)
    X_new, y_new = _data(truth, n_periods=1, n_realizations=20, seed=100, rms=0.5)

    def fitted():
        return PNLSSRegressor(3, period=N, weighting="noise", max_iter=30, random_state=0).fit(X, y)

    with mock.patch("sklearn_pnlss.estimators._statespace.random_phase_inputs", lambda *a, **k: ()):
        unchecked = fitted()
    with pytest.warns(UserWarning, match="runs away on .* of 40 new random-phase realisations"):
        checked = fitted()
    assert checked.best_iteration_ < unchecked.best_iteration_
    runaways = [sum(m.range_excursion(U[None])[0] > 1 for U in X_new) for m in (unchecked, checked)]
    assert runaways[0] >= 10 and runaways[1] == 0, runaways
    errors = [-m.score(X_new, y_new) for m in (unchecked, checked)]
    assert errors[0] > 0 and errors[1] < -25, errors


def test_a_model_that_runs_away_on_a_check_record_is_not_returned():
    """Without the new realisations, five records of the loud level given
    as ``X_check`` (inputs only, simulated from rest) stop the same
    runaway: the kept iterate runs away on none of the 15 other records."""
    truth, X, y = two_levels(n_periods=4, n_realizations=1)
    X_new, y_new = _data(truth, n_periods=1, n_realizations=20, seed=100, rms=0.5)
    with mock.patch("sklearn_pnlss.estimators._statespace.random_phase_inputs", lambda *a, **k: ()):
        with pytest.warns(UserWarning, match=r"runs away on [1-5] of the 5 check records \(X_check\[[0-4]\]"):
            checked = PNLSSRegressor(3, period=N, weighting="noise", max_iter=30, random_state=0).fit(
                X, y, X_check=list(X_new[:5]))
    others, y_others = X_new[5:], y_new[5:]
    assert sum(checked.range_excursion(U[None])[0] > 1 for U in others) == 0
    assert -checked.score(others, y_others) < -25


def test_check_records_must_have_the_training_channels_and_be_finite():
    truth = _truth(np.random.default_rng(5))
    X, y = _data(truth, n_periods=2, n_realizations=2, rms=0.3, seed=2)
    model = PNLSSRegressor(3, period=N, max_iter=2, random_state=0)
    with pytest.raises(ValueError, match="X_check has 2 input channels but X has 1"):
        model.fit(X, y, X_check=np.zeros((1, N, 2)))
    bad = X[:1].copy()
    bad[0, 3, 0] = np.nan
    with pytest.raises(ValueError, match="X_check"):
        model.fit(X, y, X_check=bad)


def test_no_check_without_periodic_inputs_and_no_warning_when_it_passes():
    truth = _truth(np.random.default_rng(5))
    X, y = _data(truth, n_periods=4, n_realizations=4, rms=0.3, seed=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", UserWarning)
        model = PNLSSRegressor(3, period=N, max_iter=10, random_state=0).fit(X, y)
    assert model.best_iteration_ == model.n_iter_
    assert random_phase_inputs(list(X[:, :N + 1]), N) == ()


@pytest.mark.slow
def test_small_data_bouc_wen_model_does_not_lose_to_its_linear_start():
    """PNLSS (3, 5, 7) on three realisations of two periods at 55 N (data
    draw 3): unchecked it ran away on one of 14 new 50 N realisations
    (+32 dB); checked, every one is far below the linear start's -76 dB."""
    from sklearn_pnlss.datasets import make_bouc_wen
    from sklearn_pnlss.metrics import rms_error

    data = make_bouc_wen(n_realizations=3, n_periods=2, rms=55.0, random_state=3, n_jobs=2)
    new = make_bouc_wen(n_realizations=14, n_periods=1, rms=50.0, noise_rms=0.0, random_state=1053, n_jobs=2)
    with pytest.warns(UserWarning, match="runs away"):
        model = PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", period=data.period, n_jobs=2,
                               random_state=0).fit(data.X_train, data.y_train)
    db = np.array([float(rms_error(b[None], model.predict(a[None]), db=True))
                   for a, b in zip(new.X_train, new.y_train)])
    assert np.max(db) < -85, db


def _oscillator(radius):
    """A two-state PNLSS model: a rotation by 0.3 rad a sample scaled by
    ``radius``, bounded by a hardening cubic on each state; above 1 at
    rest it oscillates by itself, on a limit cycle the cubic sets."""
    exE = monomial_exponents(3, (3,))
    E = np.zeros((2, len(exE)))
    for i in range(2):
        E[i, np.flatnonzero(exE[:, i] == 3)] = -0.5
    c, s = np.cos(0.3), np.sin(0.3)
    return PNLSSModel(A=radius * np.array([[c, -s], [s, c]]), B=np.array([[0.2], [0.0]]), C=np.array([[1.0, 0.0]]),
                      D=np.zeros((1, 1)), E=E, F=np.zeros((1, 0)), exE=exE,
                      exF=np.zeros((0, 3), dtype=np.int64))


def test_a_model_that_oscillates_by_itself_does_not_settle():
    """The response to a periodic input repeated from rest settles into a
    periodic steady state for a model stable at rest, and not for one
    that oscillates by itself (its own frequency is not the input's)."""
    U = 0.1 * np.sin(2 * np.pi * 3 * np.arange(N) / N)[:, None]
    assert _oscillator(0.95).settles(U)
    assert not _oscillator(1.02).settles(U)
    assert not _oscillator(1.02).settles(U, max_periods=3)


def test_the_kept_iterate_is_the_latest_that_settles_on_the_training_inputs():
    """Iterates 10 and 9 oscillate by themselves on one of two training
    inputs (and run away on none of the new ones): iterate 8 is kept and
    the report says why."""
    class StandIn:
        def __init__(self, settled):
            self.settled = settled

        def runaways_in_turn(self, inputs, stop_at_first=False):
            return []

        def settles(self, U):
            return self.settled or U[0, 0] > 0  # the second training input settles for every iterate

    order = [(k, None, np.nan, 1.0) for k in range(10, -1, -1)]
    models = {k: StandIn(k <= 8) for k in range(11)}
    training = [np.zeros((4, 1)), np.ones((4, 1))]
    kept, report = _sane_on_new_inputs(order, lambda it: models[it[0]], [np.zeros((4, 1))], training)
    assert kept[0] == 8
    assert (report.n_runaway, report.n_unsettled, report.n_training, report.kept_iteration) == (0, 1, 2, 8)
    message = report.message("the latest")
    assert "does not settle into a periodic response on 1 of its 2 periodic training inputs" in message
    assert "runs away" not in message and "iterate 8 is kept instead" in message
    settled, none = _sane_on_new_inputs(order[2:], lambda it: models[it[0]], [], training)
    assert settled[0] == 8 and none is None


@pytest.mark.parametrize("radius", [0.95, 1.05])
def test_records_simulated_side_by_side_match_one_input_at_a_time(radius):
    """A PNLSS model's kernel simulates the check's records side by side
    with the arithmetic of one input at a time: the same excursions, inf
    where the state diverges (radius 1.05: unstable once its cubic is
    held at the edge of its trusted range)."""
    from sklearn_pnlss.statespace.model_base import CHECK_RECORDS, StateSpaceModel

    model = replace(_oscillator(radius), bounds=np.array([[-0.6, 0.6], [-0.5, 0.7], [-np.inf, np.inf]]))
    rng = np.random.default_rng(4)
    U = np.stack([a * rng.standard_normal((400, 1)) for a in np.linspace(0.2, 6.0, 13)])
    side_by_side, one_at_a_time = np.full(13, np.nan), np.full(13, np.nan)
    # as runaways_in_turn deals them: 13 inputs to 8 records, 5 of them of two
    model._excursions_in_turn(U, CHECK_RECORDS, 0, CHECK_RECORDS, 1.0, False, side_by_side)
    StateSpaceModel._excursions_in_turn(model, U, CHECK_RECORDS, 0, CHECK_RECORDS, 1.0, False, one_at_a_time)
    assert np.array_equal(side_by_side, one_at_a_time)
    away = np.flatnonzero(one_at_a_time > 1.0)
    assert 0 < away.size < 13 and (radius < 1 or np.isinf(one_at_a_time).any())
    assert np.array_equal(model.runaways_in_turn(list(U)), away)
    assert model.runaways_in_turn(list(U), stop_at_first=True).size >= 1
    assert model.runaways_in_turn(list(U[:2])).size == 0  # the quiet ones alone


def test_an_iterate_worse_than_its_start_on_a_measured_check_record_is_not_kept():
    """With the check records' outputs, iterates 10 to 7 simulate both
    records worse than the start (iterate 0) does: iterate 6 is kept, and
    the report names the records."""
    class StandIn:
        def __init__(self, offset):
            self.offset = offset

        def runaways_in_turn(self, inputs, stop_at_first=False):
            return []

        def simulate_with_excursion(self, U):
            self.runs = getattr(self, "runs", 0) + 1
            return U + self.offset, 0.0  # the output, and no excursion past the range

    order = [(k, None, np.nan, 1.0) for k in range(10, -1, -1)]
    offsets = {k: (0.5 if k >= 7 else 0.1 * (7 - k) / 7) for k in range(11)}  # the start 0.1 off
    records = [np.zeros((8, 1)), np.ones((8, 1))]
    outputs = [records[0] + 0.05, records[1] + 0.05]
    models = {k: StandIn(offsets[k]) for k in range(11)}
    kept, report = _sane_on_new_inputs(order, lambda it: models[it[0]], [], (), records, outputs)
    assert kept[0] == 6
    # each record simulated once for each model probed: its output and its excursion from the one run
    assert max(getattr(m, "runs", 0) for m in models.values()) == len(records)
    assert (report.worse_records, report.runaway_records, report.kept_iteration) == ((0, 1), (), 6)
    message = report.message("the latest")
    assert "simulates 2 of the 2 check records (X_check[0], X_check[1]) from rest worse than the fit's start" in message
    kept, none = _sane_on_new_inputs(order, lambda it: StandIn(offsets[it[0]]), [], (), records)
    assert kept[0] == 10 and none is None  # without the outputs, no such check


def test_check_outputs_must_pair_with_the_check_records():
    truth = _truth(np.random.default_rng(5))
    X, y = _data(truth, n_periods=2, n_realizations=2, rms=0.3, seed=2)
    model = PNLSSRegressor(3, period=N, max_iter=2, random_state=0)
    with pytest.raises(ValueError, match="y_check was given without X_check"):
        model.fit(X, y, y_check=y[:1])
    with pytest.raises(ValueError, match="one output signal per X_check record"):
        model.fit(X, y, X_check=X, y_check=y[:1])
    model.fit(X, y, X_check=X[:1], y_check=y[:1])  # the training level's own record: the fit keeps its last iterate
    assert model.best_iteration_ == model.n_iter_
