"""PNLSSRegressor: polynomial nonlinear state-space model fitted by
Levenberg-Marquardt on the simulation error with an exact Jacobian."""
from numbers import Integral, Real

import numpy as np
from sklearn.base import _fit_context, clone
from sklearn.utils._param_validation import Interval, StrOptions

from ..frequency.noise import periodic_noise_variance
from ..metrics import to_db
from ..statespace.levenberg_marquardt import levenberg_marquardt
from ..statespace.linear import simulate_linear_signal
from ..statespace.monomials import monomial_exponents
from ..statespace.objective import SimulationError
from ..statespace.pnlss import DivergenceError, PNLSSModel
from ..statespace.segments import make_segments, transient_length
from ..utils.validation import as_signal_list, check_period, validate_signals
from ._base import SignalRegressorBase
from .bla import BLAEstimator

__all__ = ["PNLSSRegressor"]


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
        ``period``) are steady state: the end of their last period is
        prepended as a transient, so no sample is lost. Other signals are
        simulated from rest: the measurement is taken to start from rest, as
        a swept sine does; when it does not, ``n_transient`` samples are left
        out of the cost (we do not estimate an initial state: the discarded
        samples cost less than the extra parameters and their bias).
    average_periods : bool, default=True
        Fit periodic signals through their period average (the toolbox's
        practice). The model's steady-state output repeats every period, so
        the least-squares optimum is the same as on all periods, the noise
        power and the cost drop by the number of periods, and each iteration
        is that many times cheaper. Set False to fit every period (for
        instance when the first periods are not yet in steady state).
    weighting : {None, "band", "noise"}, default=None
        Weighting of the simulation error. None: time domain, all samples
        (times ``time_weight`` when given to :meth:`fit`). "band": frequency
        domain, uniform weight on the DFT bins of ``band``. "noise":
        frequency domain, each bin of ``band`` weighted by the inverse noise
        variance of the output, estimated from the spread over the periods
        (needs periodic signals with at least two periods; with ``m`` outputs
        the weight is per output, cross-covariances are ignored); the fit
        then runs twice, unweighted and then weighted from that result,
        because the weighted cost stalls when started from the linear model.
        Both frequency weightings need periodic training signals.
    band : tuple of two int or None, default=None
        First and last DFT bin (of one period) of the weighted band; bin
        ``k`` is frequency ``k * fs / period``. None: all bins, 0 to
        ``period // 2``. Bins outside the excited band still carry the
        nonlinear distortions (and the DC offset of even nonlinearities) the
        model must reproduce: narrow the band only to leave out frequencies
        where the data cannot be trusted.
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
        Print each iteration: cost in dB (rms of the weighted normalised
        error), lambda, and the validation error when validation signals are
        given.
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
        Iterations done (both stages with ``weighting="noise"``).
    cost_history_ : ndarray
        Weighted cost (sum of squared normalised errors) after each
        iteration of the last stage, its start first.
    validation_history_ : ndarray of shape (n_iter_ + 1,)
        rms error in dB on the validation signals after each iteration
        (only when validation signals were given to :meth:`fit`).
    best_iteration_ : int
        Iteration whose parameters were kept: the last one, or the one best
        on the validation signals.
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
        "average_periods": ["boolean"],
        "weighting": [None, StrOptions({"band", "noise"})],
        "band": [tuple, list, None],
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
        average_periods=True,
        weighting=None,
        band=None,
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
        self.average_periods = average_periods
        self.weighting = weighting
        self.band = band
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
    def fit(self, X, y, *, X_val=None, y_val=None, time_weight=None):
        """Fit the linear start, then the full model by Levenberg-Marquardt.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), list of
            2-D signals, or one 1-D/2-D signal
        y : signals with n_outputs channels, same layout and lengths
        X_val, y_val : signals or None, default=None
            Validation signals: the iterate with the lowest rms simulation
            error on them is kept (the toolbox's practice against
            overfitting). Periodic ones are simulated in steady state. In a
            grid search leave them out: the held-out signals of each split
            do the validation there.
        time_weight : signals or None, default=None
            Non-negative weight of the squared error at each sample, in the
            layout of ``y`` (with n_outputs channels, or one channel for all
            outputs). Only with ``weighting=None``.

        Returns
        -------
        self
        """
        X_list, y_list = self._validate_fit_data(X, y)
        period = check_period(self.period)
        weights = self._check_time_weight(time_weight, y_list)
        val = self._check_validation(X_val, y_val)
        linear = clone(self.linear_model) if self.linear_model is not None else BLAEstimator(self.n_states, period=period)
        if linear.get_params()["n_states"] != self.n_states:
            raise ValueError(
                f"linear_model has n_states={linear.n_states} but n_states={self.n_states}; make them equal."
            )
        self.linear_model_ = linear.fit(X_list, y_list)
        model = self._normalised_start(X_list, y_list, period)
        Xn = [U / self._u_scale for U in X_list]
        yn = [Y / self._y_scale for Y in y_list]
        n_tr = transient_length(model.A, period) if period else 0
        if self.n_transient != "auto":
            n_tr = int(self.n_transient)
        freq_weight = self._frequency_weight(Xn, yn, period)

        def objective(freq_weight):
            return SimulationError(make_segments(
                Xn, yn, period=period, n_transient=n_tr if period else 0,
                n_skip=0 if self.n_transient == "auto" else int(self.n_transient),
                average=self.average_periods, time_weights=weights, freq_weight=freq_weight,
            ))

        # The noise-weighted cost, dominated by the quietest bins, has poor
        # basins far from its optimum: from the linear start, LM stalls well
        # above it (measured in tests/test_pnlss_fitting.py). Starting it from
        # the unweighted optimum reaches it.
        stages = [objective(None)] if self.weighting != "band" else []
        if freq_weight is not None:
            stages.append(objective(freq_weight))
        self._fit_lm(model, stages, val)
        self._export_user_units()
        self.n_params_ = self._model.n_params
        self.n_nonlinear_params_ = self._model.E.size + self._model.F.size
        return self

    def _check_time_weight(self, time_weight, y_list):
        if time_weight is None:
            return None
        if self.weighting is not None:
            raise ValueError(
                f"time_weight is a time-domain weighting, but weighting={self.weighting!r} "
                "weights in frequency; pass one of them."
            )
        w_list, _ = as_signal_list(time_weight, name="time_weight", min_samples=1)
        p = y_list[0].shape[1]
        if len(w_list) != len(y_list) or any(
            w.shape[0] != Y.shape[0] or w.shape[1] not in (1, p) for w, Y in zip(w_list, y_list)
        ):
            raise ValueError(
                "time_weight must be given in the layout of y: one weight signal per "
                "output signal, of the same length, with n_outputs channels or one."
            )
        if any(np.any(w < 0) for w in w_list) or not any(np.any(w > 0) for w in w_list):
            raise ValueError("time_weight must be non-negative with at least one positive value.")
        return w_list

    def _check_validation(self, X_val, y_val):
        if (X_val is None) != (y_val is None):
            raise ValueError("Pass both X_val and y_val, or neither.")
        if X_val is None:
            return None
        Xv, yv, _ = validate_signals(self, X_val, y_val, reset=False)
        if yv[0].shape[1] != self.n_outputs_:
            raise ValueError(f"y_val has {yv[0].shape[1]} outputs but y has {self.n_outputs_}.")
        return Xv, yv

    def _normalised_start(self, X_list, y_list, period):
        """The linear start with unit-rms inputs, outputs and states, E = F = 0.
        High-degree monomials of order-one variables stay well conditioned."""
        lin = self.linear_model_
        A, B, C, D = lin.A_, lin.B_, lin.C_, lin.D_
        n, m, p = A.shape[0], B.shape[1], C.shape[0]
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
        self._x_scale = x_scale
        T, Ti = np.diag(x_scale), np.diag(1 / x_scale)
        Su, Sy_i = np.diag(self._u_scale), np.diag(1 / self._y_scale)
        exE, exF = self._exponents(n, m)
        return PNLSSModel(
            A=Ti @ A @ T, B=Ti @ B @ Su, C=Sy_i @ C @ T, D=Sy_i @ D @ Su,
            E=np.zeros((n, exE.shape[0])), F=np.zeros((p, exF.shape[0])), exE=exE, exF=exF,
        )

    def _frequency_weight(self, Xn, yn, period):
        """Callable giving the weight per DFT bin of a periodic segment that
        averages ``n_averaged`` periods, or None (time domain)."""
        if self.weighting is None:
            return None
        if period is None or not all(self._signal_is_periodic(U.shape[0]) for U in Xn):
            raise ValueError(
                f"weighting={self.weighting!r} weights DFT bins of a period: set period and "
                "pass steady-state signals of whole periods, or use weighting=None."
            )
        n_bins = period // 2 + 1
        lo, hi = (0, n_bins - 1) if self.band is None else map(int, self.band)
        if not 0 <= lo <= hi < n_bins:
            raise ValueError(
                f"band must be (first, last) DFT bins with 0 <= first <= last <= period // 2 = "
                f"{n_bins - 1}; got {self.band}."
            )
        in_band = np.zeros((n_bins, 1))
        in_band[lo : hi + 1] = 1.0
        if self.weighting == "band":
            return lambda n_averaged: np.repeat(in_band, yn[0].shape[1], axis=1)
        var = periodic_noise_variance(yn, period)
        if var is None:
            raise ValueError(
                "weighting='noise' estimates the noise from the spread over periods: pass "
                "periodic signals with at least two periods, or use weighting='band'."
            )
        # A noiseless bin (simulated data) would get an infinite weight.
        var = np.maximum(var, 1e-12 * np.mean(var[lo : hi + 1]) + np.finfo(float).tiny)
        return lambda n_averaged: in_band * n_averaged / var

    def _fit_lm(self, model, objectives, val):
        """Levenberg-Marquardt through each objective in turn, each stage
        starting where the previous one ended; keeps the last iterate, or
        the one best on the validation signals over all stages."""
        n = model.A.shape[0]
        val_history, best = [], {"err": np.inf, "theta": model.theta, "it": 0}
        done = 0  # iterations of the earlier stages

        def validation_error(theta):
            if val is None:
                return np.nan
            cand = model.with_theta(theta)
            try:
                err = [
                    cand.simulate_signal(U / self._u_scale, self.period if self._signal_is_periodic(U.shape[0]) else None)
                    * self._y_scale - Y
                    for U, Y in zip(*val)
                ]
            except DivergenceError:
                return np.inf
            return float(to_db(np.sqrt(np.mean(np.concatenate(err) ** 2))))

        def callback(it, theta, cost, lam):
            v = validation_error(theta)
            val_history.append(v)
            if v < best["err"]:
                best.update(err=v, theta=theta.copy(), it=done + it)
            if self.verbose:
                msg = f"iteration {done + it:4d}  cost {10 * np.log10(cost / n_res):8.2f} dB  lambda {lam:9.3g}"
                print(msg + (f"  validation {v:8.2f} dB" if val is not None else ""), flush=True)

        theta = model.theta
        for stage, objective in enumerate(objectives):
            n_res = sum(seg.Y.size for seg in objective.segments)
            e0 = objective.residual(model.with_theta(theta))
            if e0 is None:
                raise ValueError(
                    "The linear start diverges on the training data; check the data or give "
                    "a stable linear_model."
                )
            if stage == 0:
                callback(0, theta, float(e0 @ e0), np.nan)
            result = levenberg_marquardt(
                lambda th, obj=objective: obj.residual(model.with_theta(th)),
                lambda th, obj=objective: obj.normal_equations(model.with_theta(th)),
                theta, n_drop=n * n, max_iter=self.max_iter, tol=self.tol, callback=callback,
            )
            theta = result.theta
            done += result.n_iter
        keep, self.best_iteration_ = (best["theta"], best["it"]) if val is not None else (theta, done)
        self._model = model.with_theta(keep)
        self.n_iter_ = done
        self.cost_history_ = np.array([h[1] for h in result.history])
        if val is not None:
            self.validation_history_ = np.array(val_history)

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
