"""TrialColumns: many one-column fits beside fixed columns, by projection,
equal to one lstsq per column."""
import numpy as np
import pytest

from sklearn_pnlss.gap.candidates.trial_columns import TrialColumns


def _lstsq_cost(columns, fixed, target):
    A = np.column_stack([columns, fixed])
    coef = np.linalg.lstsq(A, target, rcond=None)[0]
    return coef, np.sum((target - A @ coef) ** 2)


@pytest.mark.parametrize("n_fixed", [0, 1, 3])
def test_costs_and_solution_equal_one_lstsq_per_column(n_fixed):
    rng = np.random.default_rng(n_fixed)
    n = 500
    fixed = rng.normal(size=(n, n_fixed)) * np.logspace(-3, 3, n_fixed)  # columns of very different scales
    trial = rng.normal(size=(n, 40))
    target = 2.0 * trial[:, 7] + fixed @ rng.normal(size=n_fixed) + 0.01 * rng.normal(size=n)
    trials = TrialColumns(fixed, target)
    costs = trials.costs(trial)
    expected = np.array([_lstsq_cost(trial[:, j], fixed, target)[1] for j in range(trial.shape[1])])
    np.testing.assert_allclose(costs, expected, rtol=1e-9)
    assert np.argmin(costs) == 7  # the column the target was made of
    coef, cost = trials.solve(trial[:, 7])
    assert abs(coef[0] - 2.0) < 1e-3 and np.isclose(cost, expected[7], rtol=1e-9)
    assert np.isclose(trials.base_cost, np.sum((target - fixed @ np.linalg.lstsq(fixed, target, rcond=None)[0]) ** 2)
                      if n_fixed else target @ target, rtol=1e-9)


def test_a_zero_or_dependent_column_leaves_the_base_cost():
    rng = np.random.default_rng(0)
    fixed = rng.normal(size=(200, 2))
    target = rng.normal(size=200)
    trials = TrialColumns(fixed, target)
    costs = trials.costs(np.column_stack([np.zeros(200), fixed @ [1.0, -2.0]]))
    np.testing.assert_allclose(costs, trials.base_cost, rtol=1e-9)
    # a fixed column repeated is cut as lstsq cuts it
    assert np.isclose(TrialColumns(np.column_stack([fixed, fixed[:, :1]]), target).base_cost, trials.base_cost)
