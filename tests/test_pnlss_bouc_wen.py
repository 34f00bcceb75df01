"""PNLSS on the Bouc-Wen benchmark: the published accuracy, trained on the
library's own simulated data (benchmark noise) and scored on the official
test files (../shared/data/bouc_wen when present).

Published (validation multisine): states only, degrees (2, 3): -90.35 dB;
(3, 5, 7): -98.32 dB (Noel et al. 2017); states and input, (2, 3): -94.56 dB
(the seed paper's start). Each test also bounds the sweep error, so a model
that only fits multisines would fail.
"""
import numpy as np
import pytest

from sklearn_pnlss import PNLSSRegressor
from sklearn_pnlss.datasets import load_bouc_wen_official, make_bouc_wen


@pytest.fixture(scope="module")
def official(bouc_wen_dir):
    return load_bouc_wen_official(bouc_wen_dir)


@pytest.fixture(scope="module")
def training():
    return make_bouc_wen(n_realizations=2, n_periods=2, random_state=0)


def _errors(model, official):
    return (-model.score(official.X_test_multisine, official.y_test_multisine),
            -model.score(official.X_test_sweep, official.y_test_sweep))


def test_states_degrees_2_3(training, official):
    """Measured: -91.18 dB / -97.19 dB, 30 iterations, about 3 s."""
    model = PNLSSRegressor(3, degrees=(2, 3), variables="states", period=training.period)
    model.fit(training.X_train, training.y_train)
    assert model.n_params_ == 64
    multisine, sweep = _errors(model, official)
    assert multisine < -90.0
    assert sweep < -96.5
    # Two periods averaged: the final cost sits a few dB above the noise
    # floor of the averaged output (7.4e-6 m / sqrt(2) rms), not below it.
    noise_db = 20 * np.log10(7.4e-6 / np.sqrt(2) / np.sqrt(np.mean(training.y_train**2)))
    cost_db = 10 * np.log10(model.cost_history_[-1] / (2 * training.period))
    assert noise_db < cost_db < noise_db + 25


def test_states_and_input_degrees_2_3(training, official):
    """The seed paper's start, 90 nonlinear parameters. Measured: -94.23 dB
    / -97.66 dB, 70 iterations, about 3 s."""
    model = PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=training.period, max_iter=200)
    model.fit(training.X_train, training.y_train)
    assert model.n_nonlinear_params_ == 90
    multisine, sweep = _errors(model, official)
    assert multisine < -94.0
    assert sweep < -97.0


@pytest.mark.slow
@pytest.mark.parametrize("random_state", [0, 7])
def test_states_degrees_3_5_7(official, random_state):
    """217 parameters, twenty realisations to fit and two more to keep the
    best iterate, the degrees grown one at a time (the default above degree
    3). Its error comes from the rare large excursions, which each
    realisation has its own: on five realisations it fits its own data 1.6
    dB better than new ones, on twenty the gap is 0.5 dB. Two draws of the
    data: fitted directly, the second (random_state=7) stays at -93.7 dB,
    its path passing through models that diverge on new realisations (see
    the user guide). Measured grown: -98.56 / -104.83 dB (random_state=0)
    and -98.58 / -104.75 dB (random_state=7), about 3.5 minutes each on two
    idle cores (python benchmarks/bench_pnlss.py --accuracy-only)."""
    data = make_bouc_wen(n_realizations=22, n_periods=2, random_state=random_state, n_jobs=-1)
    P = data.period
    model = PNLSSRegressor(3, degrees=(3, 5, 7), variables="states", period=P, max_iter=300, n_jobs=-1)
    model.fit(data.X_train[:20], data.y_train[:20], X_val=data.X_train[20:, P:], y_val=data.y_train[20:, P:])
    assert model.n_params_ == 217
    assert model.degree_stages_ == [(3,), (3, 5), (3, 5, 7)]
    multisine, sweep = _errors(model, official)
    assert multisine < -98.3
    assert sweep < -104.5
