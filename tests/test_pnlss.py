"""PNLSSRegressor: exact Jacobian, published parameter counts, and the
published accuracy on the Bouc-Wen benchmark."""
import numpy as np
import pytest

from sklearn_pnlss import PNLSSRegressor
from sklearn_pnlss.datasets import load_bouc_wen_official
from sklearn_pnlss.signals import multisine
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.pnlss import PNLSSModel, Segment
from jacobian_check import finite_difference_jacobian


def _random_model(rng, n=3, m=1, p=1):
    exE = monomial_exponents(n + m, (2, 3))
    exF = monomial_exponents(n + m, (2,))
    return PNLSSModel(
        A=np.diag([0.9, 0.5, 0.3]) + 0.05 * rng.standard_normal((n, n)),
        B=rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        E=0.01 * rng.standard_normal((n, len(exE))), F=0.01 * rng.standard_normal((p, len(exF))),
        exE=exE, exF=exF,
    )


def test_jacobian_is_exact():
    rng = np.random.default_rng(0)
    model = _random_model(rng)
    U = 0.3 * rng.standard_normal((200, 1))
    seg = [Segment(U, np.zeros((190, 1)), 10)]
    J = model.jacobian(seg)
    J_fd = finite_difference_jacobian(model, seg)
    assert np.abs(J - J_fd).max() < 1e-7 * np.abs(J).max()


def test_jacobian_is_exact_past_the_written_out_factors_and_rows():
    """Five states, two inputs and outputs, degree 4 over all seven
    variables: monomials of four factors and linear maps of five rows run
    past the kernels' written-out first three factors and four rows."""
    rng = np.random.default_rng(3)
    n, m, p = 5, 2, 2
    exE, exF = monomial_exponents(n + m, (2, 4)), monomial_exponents(n + m, (3,))
    A = rng.standard_normal((n, n))
    model = PNLSSModel(A=0.8 * A / np.abs(np.linalg.eigvals(A)).max(), B=rng.standard_normal((n, m)),
                       C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
                       E=0.01 * rng.standard_normal((n, len(exE))), F=0.01 * rng.standard_normal((p, len(exF))),
                       exE=exE, exF=exF)
    assert np.count_nonzero(exE, axis=1).max() == 4
    U = 0.3 * rng.standard_normal((60, m))
    seg = [Segment(U, np.zeros((55, p)), 5)]
    J = model.jacobian(seg)
    J_fd = finite_difference_jacobian(model, seg)
    assert np.abs(J - J_fd).max() < 1e-7 * np.abs(J).max()


@pytest.mark.parametrize(
    "degrees, variables, n_params, n_nonlinear",
    [((2,), "states", 34, 18), ((2, 3), "states", 64, 48), ((2, 3, 4), "states", 109, 93),
     ((2, 3, 4, 5), "states", 172, 156), ((3, 5, 7), "states", 217, 201),
     ((2, 3), "states_inputs", 106, 90)],
)
def test_published_parameter_counts(degrees, variables, n_params, n_nonlinear):
    X, _ = multisine(64, fs=1.0, f_band=(0.02, 0.4), n_periods=2, n_realizations=2, random_state=0)
    y = 1e-4 * np.roll(X, 1, axis=1)
    model = PNLSSRegressor(3, degrees=degrees, variables=variables, period=64, max_iter=0).fit(X, y)
    assert (model.n_params_, model.n_nonlinear_params_) == (n_params, n_nonlinear)


def test_recovers_a_pnlss_system_and_reports_user_units():
    """Data from a known PNLSS model with a 1e-4 output scale: the fit reaches
    the noise-free truth and E_ in user units reproduces the output."""
    rng = np.random.default_rng(1)
    truth = _random_model(rng)
    truth.F = np.zeros((1, 0))
    truth.exF = np.zeros((0, 4), dtype=np.int64)
    truth.E *= 3
    N = 256
    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=0.3, n_periods=2, n_realizations=2, random_state=2)
    y = np.stack([truth.simulate_signal(x, period=N) for x in X]) * 1e-4
    model = PNLSSRegressor(3, degrees=(2, 3), variables="states_inputs", period=N, max_iter=50).fit(X, y)
    assert -model.score(X, y) < 20 * np.log10(y.std()) - 60  # 60 dB below the output
    # The same model rebuilt from the user-unit matrices simulates the same output.
    user = PNLSSModel(model.A_, model.B_, model.C_, model.D_, model.E_, model.F_,
                      model.exponents_E_, model.exponents_F_)
    y_user = user.simulate_signal(X[0], period=N)
    np.testing.assert_allclose(y_user, model.predict(X[0]), rtol=1e-6, atol=1e-12 * np.abs(y).max())


def test_divergent_prediction_raises_clear_error():
    N = 128
    X, _ = multisine(N, fs=1.0, f_band=(0.01, 0.45), rms=0.3, n_periods=2, n_realizations=2, random_state=2)
    y = X + 0.3 * X**3
    model = PNLSSRegressor(2, degrees=(3,), variables="states_inputs", period=N, max_iter=5).fit(X, y)
    with pytest.raises(ValueError, match="outside the range it was fitted on"):
        model.predict(1e6 * X[0, :100])


def test_official_record_matches_the_peers(bouc_wen_dir):
    """States only, degrees (2, 3), official training record (periods 2-5):
    pyvib and the MATLAB toolbox reach -90.73 dB / -96.77 dB."""
    data = load_bouc_wen_official(bouc_wen_dir)
    model = PNLSSRegressor(3, degrees=(2, 3), variables="states", period=data.period, max_iter=40)
    model.fit(data.X_train, data.y_train)
    assert model.n_params_ == 64
    assert -model.score(data.X_test_multisine, data.y_test_multisine) < -90.7
    assert -model.score(data.X_test_sweep, data.y_test_sweep) < -96.7
