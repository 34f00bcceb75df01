"""PNLSSRegressor: polynomial nonlinear state-space model fitted by
Levenberg-Marquardt on the simulation error with an exact Jacobian."""
from numbers import Integral

import numpy as np
from joblib import effective_n_jobs
from sklearn.base import _fit_context, clone
from sklearn.utils._param_validation import Interval, StrOptions

from ..statespace.linear import is_stable, simulate_linear_signal
from ..statespace.monomials import monomial_exponents
from ..statespace.pnlss import DivergenceError, PNLSSModel
from ..utils.handover import detach_stage
from ..utils.validation import check_period
from ._statespace import FIT_PARAMETER_CONSTRAINTS, LMFit, StateSpaceRegressorBase
from .bla import BLAEstimator

__all__ = ["PNLSSRegressor"]


class PNLSSRegressor(StateSpaceRegressorBase):
    """Polynomial nonlinear state-space model.

    ``x(t+1) = A x + B u + E zeta(x, u)``, ``y = C x + D u + F eta(x, u)``,
    where ``zeta`` and ``eta`` hold all monomials of the chosen total degrees
    in the states (and inputs). Starts from the BLA's linear model with
    ``E = F = 0`` and fits all parameters by Levenberg-Marquardt on the
    simulation error, with the exact Jacobian from the sensitivity
    recursion (compiled), Jacobian columns scaled to unit rms, a thin SVD with
    the ``n_states**2`` smallest singular values dropped, adaptive lambda and
    the best iterate kept. An iterate whose simulation diverges is rejected.
    Degrees above 3 are added one per stage, each stage starting from the
    previous one's result (``grow_degrees``).

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
    grow_degrees : bool or "auto", default="auto"
        Fit the degrees in stages, adding one degree per stage with zero
        coefficients to the previous stage's result (its iterate best on the
        validation signals when they are given), the last stage fitting all
        of them. High-degree terms then grow from a model that already
        captures the main nonlinearity, instead of from the linear start,
        where Levenberg-Marquardt's first large steps can lead through
        models that fit the training signals but diverge beyond their range.
        True: the lowest degree alone first. "auto": the degrees up to 3
        together first (for (2, 3), one stage), then each higher one. False:
        all degrees at once. Measured on Bouc-Wen, states only, degrees
        (3, 5, 7), twenty realisations, 300 iterations: -98.56 dB on the
        official test multisine instead of -98.02 dB, and -98.58 dB instead
        of -93.69 dB on another draw of the data; degrees (2, 3) grown from
        degree 2 alone reach -87.95 dB instead of -90.73 dB (official
        record).
    extrapolation : {"hold", "polynomial"}, default="hold"
        What the polynomial does where the model's states or inputs leave
        the range they covered in training (widened by ``range_margin``).
        "hold": the monomials are evaluated at the states held at the edge
        of that box, so for a bounded input they stay bounded, and a stable
        ``A`` gives a bounded state for every bounded input: the model cannot
        run away on a new signal of the training kind and level (bounded by
        construction). Inside the box nothing changes. "polynomial": the
        plain polynomial everywhere, as fitted (right when the system's
        nonlinearity is known to be that polynomial).
    range_margin : float, default=0.05
        Widening of the trusted range on each side, as a fraction of its
        width. Measured on Bouc-Wen, degrees (2, 3), official test multisine
        (whose peaks take the states slightly past their training range):
        0.05 gives the plain polynomial's -94.23 dB (states and input), 0
        gives -93.97 dB.
    max_iter : int, default=100
        Levenberg-Marquardt iterations at most (of the last stage when the
        degrees grow; each earlier one runs at most ``max_iter // 2``).
    tol : float, default=1e-8
        Stop when an iteration lowers the cost by less than this fraction.
    n_transient : int or "auto", default="auto"
        Samples prepended (periodic signals) or left out of the cost (other
        signals). "auto": the decay time of the linear start's slowest pole,
        at most a period, for periodic signals; 0 for the others.
    linear_model : BLAEstimator or None, default=None
        Estimator of the linear start (cloned before fitting); None uses
        ``BLAEstimator(n_states, period=period)``. In a Pipeline after a
        ``BLAEstimator`` stage, that fitted stage is the start instead
        (``make_pipeline(BLAEstimator(3, period=P), PNLSSRegressor(3, period=P))``).
    n_jobs : int or None, default=None
        Threads over the training signals for the simulations and the
        Jacobian (the compiled kernels and the BLAS products release the GIL;
        each thread runs BLAS single-threaded). Worth it with many signals:
        twenty Bouc-Wen realisations, degrees (3, 5, 7), two cores: 1.2 to
        1.5 times faster per iteration. None means 1, -1 all cores; leave it
        at None inside a parallel grid search.
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
    trusted_range_ : ndarray of shape (n_states + n_inputs, 2)
        Box of ``[x; u]`` (user units) inside which the polynomial is
        evaluated as fitted (see ``extrapolation``): the states' range, the
        inputs unbounded; infinite with ``extrapolation="polynomial"``.
    n_params_, n_nonlinear_params_ : int
    n_iter_ : int
        Iterations done, all stages counted (the degrees grown one at a
        time, both weightings with ``weighting="noise"``).
    cost_history_ : ndarray
        Weighted cost (sum of squared normalised errors) after each
        iteration of the last stage, its start first.
    validation_history_ : ndarray of shape (``n_iter_ + 1``,)
        rms error in dB on the validation signals after each iteration,
        all stages in turn (only when validation signals were given to
        :meth:`fit`).
    best_iteration_ : int
        Iteration whose parameters were kept, counted over all stages: the
        last one, or the one best on the validation signals.
    degree_stages_ : list of tuple of int
        The degrees of each stage: one stage with all degrees, or one more
        degree per stage when they grow.
    n_features_in_, n_outputs_ : int

    Examples
    --------
    >>> from sklearn_pnlss import PNLSSRegressor
    >>> PNLSSRegressor(n_states=3, degrees=(2, 3), variables="states").get_params()["degrees"]
    (2, 3)
    """

    _parameter_constraints = {
        **FIT_PARAMETER_CONSTRAINTS,
        "n_states": [Interval(Integral, 1, None, closed="left")],
        "degrees": ["array-like"],
        "variables": [StrOptions({"states_inputs", "states"})],
        "equations": [StrOptions({"state", "output", "both"})],
        "grow_degrees": ["boolean", StrOptions({"auto"})],
        "extrapolation": [StrOptions({"hold", "polynomial"})],
        "linear_model": [None, BLAEstimator],
        "n_jobs": [Integral, None],
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
        grow_degrees="auto",
        extrapolation="hold",
        range_margin=0.05,
        max_iter=100,
        tol=1e-8,
        n_transient="auto",
        linear_model=None,
        n_jobs=None,
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
        self.grow_degrees = grow_degrees
        self.extrapolation = extrapolation
        self.range_margin = range_margin
        self.max_iter = max_iter
        self.tol = tol
        self.n_transient = n_transient
        self.linear_model = linear_model
        self.n_jobs = n_jobs
        self.verbose = verbose
        self.random_state = random_state

    def _degrees(self):
        degrees = sorted({int(d) for d in np.atleast_1d(self.degrees)})
        if any(d < 2 for d in degrees):
            raise ValueError(f"degrees must all be >= 2 (the linear terms are in A, B, C, D); got {self.degrees}.")
        return degrees

    def _degree_stages(self):
        degrees = self._degrees()
        if self.grow_degrees is False:
            return [tuple(degrees)]
        # "auto" fits degrees up to 3 together: degree 2 alone, an even
        # nonlinearity, leads the fit of (2, 3) to a worse optimum.
        n_first = max(sum(d <= 3 for d in degrees), 1) if self.grow_degrees == "auto" else 1
        return [tuple(degrees[:k]) for k in range(n_first, len(degrees) + 1)]

    def _exponents(self, n, m):
        degrees = self._degrees()
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
        X, stage = detach_stage(X)
        X_list, y_list = self._validate_fit_data(X, y)
        period = check_period(self.period)
        weights = self._check_time_weight(time_weight, y_list)
        val = self._check_validation(X_val, y_val)
        self.linear_model_ = self._linear_start(stage, X_list, y_list, period)
        model = self._normalised_start(X_list, y_list, period)
        try:
            self._fit_nonlinear(model, X_list, y_list, period, weights, val)
        except DivergenceError:
            raise ValueError(
                "The linear start diverges on the training data; check the data or give "
                "a stable linear_model."
            ) from None
        self._export_user_units()
        self.n_params_ = self._model.n_params
        self.n_nonlinear_params_ = self._model.E.size + self._model.F.size
        return self

    def _linear_start(self, stage, X_list, y_list, period):
        """The fitted BLA handed over by the previous Pipeline stage, or a
        clone of ``linear_model`` fitted here."""
        if stage is not None:
            if not isinstance(stage, BLAEstimator):
                raise TypeError(
                    f"PNLSSRegressor starts from a BLAEstimator stage; the previous Pipeline "
                    f"stage is a {type(stage).__name__}."
                )
            linear = stage
        else:
            linear = clone(self.linear_model) if self.linear_model is not None else BLAEstimator(self.n_states, period=period)
        if linear.get_params()["n_states"] != self.n_states:
            raise ValueError(
                f"The linear model has n_states={linear.n_states} but n_states={self.n_states}; make them equal."
            )
        if stage is None:
            linear.fit(X_list, y_list)
        if not is_stable(linear.A_):
            rho = np.max(np.abs(np.linalg.eigvals(linear.A_)))
            raise ValueError(
                f"The linear start diverges: its A has spectral radius {rho:.4g} >= 1. Give a "
                "stable linear model (BLAEstimator stabilises the ones it fits)."
            )
        return linear

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

    def _fit_nonlinear(self, model, X_list, y_list, period, weights, val):
        """LM on the full model, or stage by stage on growing degrees; sets
        the fitted attributes."""
        self.degree_stages_ = self._degree_stages()
        objectives = self._objectives(X_list, y_list, period, weights, model.A)
        fits, previous = [], None
        for k, degrees in enumerate(self.degree_stages_):
            last = k == len(self.degree_stages_) - 1
            stage_model = _with_degrees(model, degrees, previous)
            if self.verbose and len(self.degree_stages_) > 1:
                print(f"degrees {degrees}", flush=True)
            # The frequency weighting, when asked for, refines the last stage only.
            fit = self._optimise(stage_model, objectives if last else objectives[:1], val,
                                 max_iter=self.max_iter if last else self.max_iter // 2)
            fits.append(fit)
            previous = fit.model
        self._set_fit_result(_chain_stages(fits))

    def _segment_threads(self):
        # None is 1 even inside a joblib backend context (a grid search's
        # workers): threads there would oversubscribe the workers' cores.
        return 1 if self.n_jobs is None else effective_n_jobs(self.n_jobs)

    def _summary_structure(self):
        return {
            "degrees": tuple(int(d) for d in np.atleast_1d(self.degrees)),
            "variables": "states and inputs" if self.variables == "states_inputs" else "states",
            "monomials": {"state_equation": int(self.exponents_E_.shape[0]),
                          "output_equation": int(self.exponents_F_.shape[0])},
        }

    def _export_user_units(self):
        """Matrices in the user's units from the normalised model."""
        mdl = self._model
        T, Sy = self._export_linear_user_units()
        var_scale = np.concatenate([self._x_scale, self._u_scale])
        # zeta(x_n, u_n)_j = zeta_j(x, u) / prod(scale ** exponent)
        self.E_ = T @ mdl.E / np.prod(var_scale ** mdl.exE, axis=1)
        self.F_ = Sy @ mdl.F / np.prod(var_scale ** mdl.exF, axis=1)
        self.exponents_E_ = mdl.exE.copy()
        self.exponents_F_ = mdl.exF.copy()
        self.trusted_range_ = mdl.bounds * var_scale[:, None]


def _with_degrees(full, degrees, previous):
    """``full`` (E = F = 0) restricted to the monomials of ``degrees``, with
    the coefficients of ``previous``, the fit on ``degrees[:-1]`` (or None)."""
    parts = {}
    for name, ex, coef in (("E", full.exE, full.E), ("F", full.exF, full.F)):
        keep = np.isin(ex.sum(axis=1), degrees)
        parts[name], parts["ex" + name] = np.zeros_like(coef[:, keep]), ex[keep]
        if previous is not None:
            # Both keep the full model's column order, so the held columns line up.
            held = np.isin(ex[keep].sum(axis=1), degrees[:-1])
            parts[name][:, held] = getattr(previous, name)
    linear = previous if previous is not None else full
    return PNLSSModel(A=linear.A.copy(), B=linear.B.copy(), C=linear.C.copy(), D=linear.D.copy(), **parts)


def _chain_stages(fits):
    """One LMFit from consecutive stages, each starting where the previous
    ended: iterations and validation history run on across the stages."""
    if len(fits) == 1:
        return fits[0]
    last, done, best = fits[-1], fits[0].n_iter, fits[0].best_iteration
    for fit in fits[1:]:
        # Iteration 0 of a stage is the previous stage's kept iterate.
        if fit.best_iteration > 0:
            best = done + fit.best_iteration
        done += fit.n_iter
    val = None
    if last.validation_history is not None:
        # Each later stage's start repeats the previous stage's kept iterate.
        val = np.concatenate([fits[0].validation_history] + [f.validation_history[1:] for f in fits[1:]])
    return LMFit(
        model=last.model, n_iter=done, best_iteration=best,
        cost_history=last.cost_history, validation_history=val, validation_error=last.validation_error,
    )
