"""PNLSSRegressor: polynomial nonlinear state-space model fitted by
Levenberg-Marquardt on the simulation error with an exact Jacobian."""
from numbers import Integral, Real

import numpy as np
from sklearn.base import _fit_context, clone
from sklearn.utils._param_validation import Interval, StrOptions

from ..statespace.levenberg_marquardt import levenberg_marquardt
from ..statespace.linear import simulate_linear_signal
from ..statespace.monomials import monomial_exponents
from ..statespace.pnlss import DivergenceError, PNLSSModel, Segment
from ..utils.validation import check_period
from ._base import SignalRegressorBase
from .bla import BLAEstimator

__all__ = ["PNLSSRegressor"]


def _transient_length(A, period, tol=1e-9):
    """Samples for the slowest linear mode to decay by ``tol``, at most one
    period (prepending a whole period is always enough for a stable model)."""
    rho = np.max(np.abs(np.linalg.eigvals(A)))
    n = int(np.ceil(np.log(tol) / np.log(rho))) if 0 < rho < 1 else period
    return int(np.clip(n, 10, period))


class PNLSSRegressor(SignalRegressorBase):
    """Polynomial nonlinear state-space model.

    ``x(t+1) = A x + B u + E zeta(x, u)``, ``y = C x + D u + F eta(x, u)``,
    where ``zeta`` and ``eta`` hold all monomials of the chosen total degrees
    in the states (and inputs). Starts from the BLA's linear model with
    ``E = F = 0`` and fits all parameters by Levenberg-Marquardt on the
    simulation error, with the exact Jacobian from the sensitivity
    recursion (compiled), Jacobian columns scaled to unit rms, a thin SVD with
    the ``n_states**2`` smallest singular values dropped, adaptive lambda and
    the best iterate kept. An iterate whose simulation diverges is rejected.

    Inputs, outputs and states are normalised internally (unit rms) so that
    high-degree monomials stay well conditioned; the reported matrices are in
    the user's units.

    Parameters
    ----------
    n_states : int, default=3
        Model order.
    degrees : tuple of int, default=(2, 3)
        Total degrees of the monomials, e.g. ``(2, 3)`` or ``(3, 5, 7)``.
    variables : {"states_inputs", "states"}, default="states_inputs"
        Variables of the monomials.
    equations : {"state", "output", "both"}, default="state"
        Equations that carry the nonlinear terms.
    period : int or None, default=None
        Samples per period. Periodic training signals (length a multiple of
        ``period``) get the end of their last period prepended as a transient,
        so no sample is lost; other signals are simulated from rest (the
        measurement is taken to start from rest; use ``n_transient`` to leave
        samples out of the cost otherwise).
    max_iter : int, default=100
        Levenberg-Marquardt iterations at most.
    tol : float, default=1e-8
        Stop when an iteration lowers the cost by less than this fraction.
    n_transient : int or "auto", default="auto"
        Samples prepended (periodic signals) or left out of the cost (other
        signals). "auto": the decay time of the linear start's slowest pole,
        at most a period, for periodic signals; 0 for the others.
    linear_model : BLAEstimator or None, default=None
        Estimator of the linear start (cloned before fitting); None uses
        ``BLAEstimator(n_states, period=period)``.
    verbose : int, default=0
        Print the iterations (cost in dB, lambda).
    random_state : int, RandomState instance or None, default=None
        Unused by the deterministic fit; kept for API consistency.

    Attributes
    ----------
    A_, B_, C_, D_, E_, F_ : ndarray
        Model matrices in the user's units.
    exponents_E_, exponents_F_ : ndarray of int of shape (n_terms, n_states + n_inputs)
        Monomial exponents over ``[x; u]`` of the columns of ``E_`` and ``F_``.
    linear_model_ : BLAEstimator
        The fitted linear start.
    n_params_, n_nonlinear_params_ : int
    n_iter_ : int
    cost_history_ : ndarray of shape (n_iter + 1,)
        Cost (sum of squared normalised errors) after each iteration.
    n_features_in_, n_outputs_ : int

    Examples
    --------
    >>> from sklearn_pnlss import PNLSSRegressor
    >>> PNLSSRegressor(n_states=3, degrees=(2, 3), variables="states").get_params()["degrees"]
    (2, 3)
    """

    _parameter_constraints = {
        "n_states": [Interval(Integral, 1, None, closed="left")],
        "degrees": ["array-like"],
        "variables": [StrOptions({"states_inputs", "states"})],
        "equations": [StrOptions({"state", "output", "both"})],
        "period": [Interval(Integral, 2, None, closed="left"), None],
        "max_iter": [Interval(Integral, 0, None, closed="left")],
        "tol": [Interval(Real, 0, None, closed="left")],
        "n_transient": [Interval(Integral, 0, None, closed="left"), StrOptions({"auto"})],
        "linear_model": [None, BLAEstimator],
        "verbose": ["verbose"],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        n_states=3,
        *,
        degrees=(2, 3),
        variables="states_inputs",
        equations="state",
        period=None,
        max_iter=100,
        tol=1e-8,
        n_transient="auto",
        linear_model=None,
        verbose=0,
        random_state=None,
    ):
        self.n_states = n_states
        self.degrees = degrees
        self.variables = variables
        self.equations = equations
        self.period = period
        self.max_iter = max_iter
        self.tol = tol
        self.n_transient = n_transient
        self.linear_model = linear_model
        self.verbose = verbose
        self.random_state = random_state

    def _exponents(self, n, m):
        degrees = [int(d) for d in np.atleast_1d(self.degrees)]
        if any(d < 2 for d in degrees):
            raise ValueError(f"degrees must all be >= 2 (the linear terms are in A, B, C, D); got {self.degrees}.")
        active = np.ones(n + m, dtype=bool)
        if self.variables == "states":
            active[n:] = False
        ex = monomial_exponents(n + m, degrees, active)
        none = np.zeros((0, n + m), dtype=np.int64)
        exE = ex if self.equations in ("state", "both") else none
        exF = ex if self.equations in ("output", "both") else none
        return exE, exF

    @_fit_context(prefer_skip_nested_validation=False)
    def fit(self, X, y):
        """Fit the linear start, then the full model by Levenberg-Marquardt.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), list of
            2-D signals, or one 1-D/2-D signal
        y : signals with n_outputs channels, same layout and lengths

        Returns
        -------
        self
        """
        X_list, y_list = self._validate_fit_data(X, y)
        period = check_period(self.period)
        linear = clone(self.linear_model) if self.linear_model is not None else BLAEstimator(self.n_states, period=period)
        if linear.get_params()["n_states"] != self.n_states:
            raise ValueError(
                f"linear_model has n_states={linear.n_states} but n_states={self.n_states}; make them equal."
            )
        self.linear_model_ = linear.fit(X_list, y_list)
        A, B, C, D = (self.linear_model_.A_, self.linear_model_.B_, self.linear_model_.C_, self.linear_model_.D_)
        n, m, p = A.shape[0], B.shape[1], C.shape[0]

        # Normalisation: unit-rms inputs, outputs and (linear-model) states.
        self._u_scale = np.sqrt(np.mean(np.concatenate(X_list) ** 2, axis=0))
        self._y_scale = np.sqrt(np.mean(np.concatenate(y_list) ** 2, axis=0))
        if np.any(self._u_scale == 0):
            raise ValueError("An input of X is identically zero: no excitation to identify a model from.")
        self._y_scale[self._y_scale == 0] = 1.0
        states = []
        for U in X_list:
            per = period if self._signal_is_periodic(U.shape[0]) else None
            # Output the states themselves (C = I, D = 0) to measure their rms.
            states.append(simulate_linear_signal(A, B, np.eye(n), np.zeros((n, m)), U, periodic_with=per))
        x_scale = np.sqrt(np.mean(np.concatenate(states) ** 2, axis=0))
        x_scale[x_scale == 0] = 1.0
        T, Ti = np.diag(x_scale), np.diag(1 / x_scale)
        Su, Sy_i = np.diag(self._u_scale), np.diag(1 / self._y_scale)
        self._x_scale = x_scale
        exE, exF = self._exponents(n, m)
        model = PNLSSModel(
            A=Ti @ A @ T, B=Ti @ B @ Su, C=Sy_i @ C @ T, D=Sy_i @ D @ Su,
            E=np.zeros((n, exE.shape[0])), F=np.zeros((p, exF.shape[0])), exE=exE, exF=exF,
        )
        segments = self._segments(X_list, y_list, period, model.A)

        def callback(it, cost, lam):
            if self.verbose:
                print(f"iteration {it:4d}  cost {10 * np.log10(cost / n_res):8.2f} dB  lambda {lam:9.3g}", flush=True)

        n_res = sum(s.Y.size for s in segments)
        result = levenberg_marquardt(
            lambda th: model.with_theta(th).residual(segments),
            lambda th: model.with_theta(th).jacobian(segments),
            model.theta, n_drop=n * n, max_iter=self.max_iter, tol=self.tol, callback=callback,
        )
        self._model = model.with_theta(result.theta)
        self.n_iter_ = result.n_iter
        self.cost_history_ = np.array([h[1] for h in result.history])
        self._export_user_units()
        self.n_params_ = self._model.n_params
        self.n_nonlinear_params_ = self._model.E.size + self._model.F.size
        return self

    def _segments(self, X_list, y_list, period, A):
        segs = []
        for U, Y in zip(X_list, y_list):
            Un, Yn = U / self._u_scale, Y / self._y_scale
            if self._signal_is_periodic(U.shape[0]):
                n_tr = _transient_length(A, period) if self.n_transient == "auto" else int(self.n_transient)
                n_tr = min(n_tr, U.shape[0])
                segs.append(Segment(np.vstack([Un[U.shape[0] - n_tr :], Un]), Yn, n_tr))
            else:
                n_skip = 0 if self.n_transient == "auto" else min(int(self.n_transient), U.shape[0] - 1)
                segs.append(Segment(Un, Yn[n_skip:], n_skip))
        return segs

    def _export_user_units(self):
        """Matrices in the user's units from the normalised model."""
        mdl = self._model
        T, Ti = np.diag(self._x_scale), np.diag(1 / self._x_scale)
        Su_i, Sy = np.diag(1 / self._u_scale), np.diag(self._y_scale)
        var_scale = np.concatenate([self._x_scale, self._u_scale])
        self.A_ = T @ mdl.A @ Ti
        self.B_ = T @ mdl.B @ Su_i
        self.C_ = Sy @ mdl.C @ Ti
        self.D_ = Sy @ mdl.D @ Su_i
        # zeta(x_n, u_n)_j = zeta_j(x, u) / prod(scale ** exponent)
        self.E_ = T @ mdl.E / np.prod(var_scale ** mdl.exE, axis=1)
        self.F_ = Sy @ mdl.F / np.prod(var_scale ** mdl.exF, axis=1)
        self.exponents_E_ = mdl.exE.copy()
        self.exponents_F_ = mdl.exF.copy()

    def _predict_signal(self, U, periodic):
        Un = U / self._u_scale
        try:
            Yn = self._model.simulate_signal(Un, self.period if periodic else None)
        except DivergenceError as exc:
            raise ValueError(
                f"{type(self).__name__}.predict: {exc}; the input drives the model far "
                "outside the range it was fitted on (larger amplitude or other "
                "frequencies than the training data)."
            ) from None
        return Yn * self._y_scale
