"""What the nonlinear state-space regressors share: the weighted
simulation-error objectives on internally scaled signals, Levenberg-Marquardt
with validation, and simulation for predict."""
import warnings
from dataclasses import dataclass, replace
from numbers import Integral, Real

import numpy as np
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted

from ..decoupling.start import states_inputs_trajectory
from ..frequency.noise import periodic_noise_variance
from ..metrics import to_db
from ..statespace.levenberg_marquardt import levenberg_marquardt
from ..statespace.model_base import DivergenceError
from ..statespace.objective import SimulationError
from ..statespace.segments import make_segments, transient_length
from ..utils.validation import as_signal_list, validate_signals
from ._base import SignalRegressorBase

__all__ = ["LMFit", "StateSpaceRegressorBase"]


@dataclass
class LMFit:
    """Outcome of one Levenberg-Marquardt run (see ``_optimise``)."""

    model: object
    n_iter: int
    best_iteration: int
    cost_history: np.ndarray
    validation_history: np.ndarray | None
    validation_error: float  # dB, best over the iterations; NaN without validation


# An iterate (or a start) that runs away (diverges, or leaves its trusted
# range by more than its width) on the validation inputs amplified by this
# factor counts as failed: a returned model must stay sane somewhat above the
# level it was validated at.
AMPLIFIED_VALIDATION = 1.2

# Constraints of the fit parameters every subclass has (see the docstring).
FIT_PARAMETER_CONSTRAINTS = {
    "range_margin": [Interval(Real, 0, None, closed="left")],
    "period": [Interval(Integral, 2, None, closed="left"), None],
    "average_periods": ["boolean"],
    "weighting": [None, StrOptions({"band", "noise"})],
    "band": [tuple, list, None],
    "max_iter": [Interval(Integral, 0, None, closed="left")],
    "tol": [Interval(Real, 0, None, closed="left")],
    "n_transient": [Interval(Integral, 0, None, closed="left"), StrOptions({"auto"})],
    "verbose": ["verbose"],
    "random_state": ["random_state"],
}


class StateSpaceRegressorBase(SignalRegressorBase):
    """Base of the regressors fitted by Levenberg-Marquardt on the
    simulation error of a :class:`~sklearn_pnlss.statespace.model_base.StateSpaceModel`.

    Subclasses build a start model in normalised units (inputs and outputs
    divided by ``_u_scale`` / ``_y_scale``) and call :meth:`_fit_nonlinear`;
    the fitted model is ``_model``. They need the parameters ``period``,
    ``average_periods``, ``weighting``, ``band``, ``max_iter``, ``tol``,
    ``n_transient``, ``extrapolation``, ``range_margin`` and ``verbose``.

    Levenberg-Marquardt fits the plain polynomial; every iterate scored on
    validation signals, and the returned model, carry the trusted range of
    their nonlinearity (the range its variables cover along the simulation of
    the training segments, widened by ``range_margin``), continued outside
    it as ``extrapolation`` says. Inside the range nothing changes.
    """

    def _fit_nonlinear(self, model, X_list, y_list, period, weights, val):
        """LM from ``model`` (normalised units) on the training signals; sets
        the fitted attributes."""
        self._set_fit_result(self._optimise(model, self._objectives(X_list, y_list, period, weights, model.A), val))

    def _objectives(self, X_list, y_list, period, weights, A):
        """The LM stages: the (time-weighted) simulation error, then the
        frequency-weighted one when ``weighting`` asks for it."""
        Xn = [U / self._u_scale for U in X_list]
        yn = [Y / self._y_scale for Y in y_list]
        n_tr = transient_length(A, period) if period else 0
        if self.n_transient != "auto":
            n_tr = int(self.n_transient)
        freq_weight = self._frequency_weight(Xn, yn, period)

        def objective(freq_weight):
            return SimulationError(make_segments(
                Xn, yn, period=period, n_transient=n_tr if period else 0,
                n_skip=0 if self.n_transient == "auto" else int(self.n_transient),
                average=self.average_periods, time_weights=weights, freq_weight=freq_weight,
            ), n_threads=self._segment_threads())

        # The noise-weighted cost, dominated by the quietest bins, has poor
        # basins far from its optimum: from the linear start, LM stalls well
        # above it (measured in tests/test_pnlss_fitting.py). Starting it from
        # the unweighted optimum reaches it.
        stages = [objective(None)] if self.weighting != "band" else []
        if freq_weight is not None:
            stages.append(objective(freq_weight))
        return stages

    def _segment_threads(self):
        """Threads over the training segments (subclasses with an ``n_jobs``
        for something else keep 1)."""
        return 1

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

    def _optimise(self, model, objectives, val, max_iter=None):
        """Levenberg-Marquardt through each objective in turn, each stage
        starting where the previous one ended and running at most
        ``max_iter`` (default ``self.max_iter``) iterations; keeps the last
        iterate, or the one best on the validation signals over all stages.
        Pure (no attribute set), so that several starts can run in parallel."""
        max_iter = self.max_iter if max_iter is None else max_iter
        val_history, best = [], {"err": np.inf, "theta": model.theta, "it": 0}
        done = 0  # iterations of the earlier stages

        segments = objectives[0].segments

        def validation_error(theta):
            if val is None:
                return np.nan
            cand = self._trusted_model(model.with_theta(theta), segments)
            err = []
            for U, Y in zip(*val):
                per = self.period if self._signal_is_periodic(U.shape[0]) else None
                try:
                    err.append(cand.simulate_signal(U / self._u_scale, per) * self._y_scale - Y)
                except DivergenceError:
                    return np.inf
                if cand.runs_away(AMPLIFIED_VALIDATION * U / self._u_scale, per):
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
                raise DivergenceError("the start model diverges on the training data")
            if stage == 0:
                callback(0, theta, float(e0 @ e0), np.nan)
            result = levenberg_marquardt(
                lambda th, obj=objective: obj.residual(model.with_theta(th)),
                lambda th, obj=objective: obj.normal_equations(model.with_theta(th)),
                theta, n_drop=self._n_null_directions(model), max_iter=max_iter, tol=self.tol, callback=callback,
            )
            theta = result.theta
            done += result.n_iter
        keep, best_it = (best["theta"], best["it"]) if val is not None else (theta, done)
        return LMFit(
            model=self._trusted_model(model.with_theta(keep), segments), n_iter=done, best_iteration=best_it,
            cost_history=np.array([h[1] for h in result.history]),
            validation_history=np.array(val_history) if val is not None else None,
            validation_error=best["err"] if val is not None else np.nan,
        )

    def _trusted_model(self, model, segments):
        """``model`` with the trusted range of its nonlinearity along its
        simulation of the training ``segments`` (see the class docstring)."""
        if self.extrapolation == "polynomial":
            return model.without_bounds()
        # From rest, as the cost simulates each segment.
        trajectory = states_inputs_trajectory(model, [seg.U for seg in segments])
        trusted = model.with_trusted_range(trajectory, self.range_margin)
        return replace(trusted, linear_extrapolation=True) if self.extrapolation == "linear" else trusted

    def _set_fit_result(self, fit):
        rho = np.max(np.abs(np.linalg.eigvals(fit.model.A)))
        if self.extrapolation != "polynomial" and rho >= 1:
            # The hold bounds the nonlinear term; only a stable A turns that
            # into a bounded state.
            warnings.warn(
                f"The fitted linear part A has spectral radius {rho:.4g} >= 1: holding the "
                "nonlinearity at its trusted range no longer bounds the state. Pass validation "
                "signals (X_val, y_val) or fewer iterations (max_iter).", UserWarning, stacklevel=3,
            )
        self._model = fit.model
        self.n_iter_ = fit.n_iter
        self.best_iteration_ = fit.best_iteration
        self.cost_history_ = fit.cost_history
        if fit.validation_history is not None:
            self.validation_history_ = fit.validation_history

    def _predict_signal(self, U, periodic):
        Un = U / self._u_scale
        try:
            Yn = self._model.simulate_signal(Un, self.period if periodic else None)
        except DivergenceError as exc:
            raise DivergenceError(
                f"{type(self).__name__}.predict: {exc}; the input X drives the model far "
                "outside the range it was fitted on (larger amplitude or other "
                "frequencies than the training data).", sample=exc.sample,
            ) from None
        return Yn * self._y_scale

    def range_excursion(self, X):
        """How far each signal takes the model past the range it was fitted
        on: before trusting a prediction on a new measurement, check it.

        The model is simulated on each signal (in periodic steady state when
        it is periodic), and the largest excursion of its nonlinearity's
        variables (the states for :class:`PNLSSRegressor`, the branch inputs
        for :class:`DecoupledPNLSSRegressor`) beyond their trusted range
        (``trusted_range_``) is given as a fraction of that range's width.

        Parameters
        ----------
        X : signals, as in :meth:`predict`

        Returns
        -------
        excursion : ndarray of shape (n_signals,)
            0 inside the range; 0.1 means 10 % of the range's width beyond
            its edge, where the nonlinearity is held (``extrapolation``); inf
            where the simulation diverges. With
            ``extrapolation="polynomial"``, 0 unless it diverges.

        Examples
        --------
        >>> import numpy as np
        >>> from sklearn_pnlss import PNLSSRegressor
        >>> from sklearn_pnlss.signals import multisine
        >>> X, _ = multisine(128, fs=100.0, f_band=(1, 40), n_periods=2, n_realizations=2, random_state=0)
        >>> y = X + 0.2 * X**2
        >>> model = PNLSSRegressor(1, degrees=(2,), period=128, max_iter=5).fit(X, y)
        >>> bool(model.range_excursion(X).max() <= model.range_margin)
        True
        >>> bool(model.range_excursion(3 * X).max() > 1)
        True
        """
        check_is_fitted(self)
        X_list, _, _ = validate_signals(self, X, reset=False, min_samples=1)
        return np.array([
            self._model.range_excursion(U / self._u_scale, self.period if self._signal_is_periodic(U.shape[0]) else None)
            for U in X_list
        ])

    def _export_linear_user_units(self):
        """``A_, B_, C_, D_`` in the user's units from the normalised model;
        returns the state and output scalings ``T``, ``Sy`` (diagonal) for
        the subclass's nonlinear blocks."""
        mdl = self._model
        T, Ti = np.diag(self._x_scale), np.diag(1 / self._x_scale)
        Su_i, Sy = np.diag(1 / self._u_scale), np.diag(self._y_scale)
        self.A_ = T @ mdl.A @ Ti
        self.B_ = T @ mdl.B @ Su_i
        self.C_ = Sy @ mdl.C @ Ti
        self.D_ = Sy @ mdl.D @ Su_i
        return T, Sy

    def _n_null_directions(self, model):
        """Parameter directions that leave the output unchanged (dropped
        from each LM step): the n^2 of the state basis."""
        return model.n_states**2
