"""PNLSSRegressor: polynomial nonlinear state-space model fitted by
Levenberg-Marquardt on the simulation error with an exact Jacobian."""
from dataclasses import replace
from numbers import Integral

import numpy as np
from joblib import effective_n_jobs
from sklearn.base import clone

from ..statespace.linear import is_stable
from ..statespace.monomials import monomial_exponents
from ..statespace.degree_growth import degree_stages, optimise_growing_degrees
from ..statespace.model_base import DivergenceError
from ..utils.parameters import Interval, Options
from ._statespace import FIT_PARAMETER_CONSTRAINTS, StateSpaceRegressorBase
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
        ``()``: no monomials, the linear model itself fitted on the
        simulation error (an output-error refinement of the BLA, which
        fits the FRF instead: the better linear simulator, and consistent
        where the BLA's H1 estimate is biased, such as data measured in
        closed loop).
    variables : {"states_inputs", "states"}, default="states_inputs"
        Variables of the monomials.
    equations : {"state", "output", "both"}, default="state"
        Equations that carry the nonlinear terms.
    period : int or None, default=None
        Samples per period; None: the period of the Pipeline stage this
        model starts from (a ``BLAEstimator(period=P)`` before it), if any,
        else no period (``period_`` holds the one used). Periodic training signals (length a multiple of
        ``period``) are steady state: the end of their last period is
        prepended as a transient, so no sample is lost. Other signals
        start from the state their first samples show (see
        ``n_transient``): a record cut from a longer run does not start from
        rest, and one that does gets a state near zero.
    average_periods : bool, default=True
        Fit periodic signals through their period average (the toolbox's
        practice). The model's steady-state output repeats every period, so
        the least-squares optimum is the same as on all periods, the noise
        power and the cost drop by the number of periods, and each iteration
        is that many times cheaper. Set False to fit every period (for
        instance when the first periods are not yet in steady state).
    weighting : {None, "relative", "band", "noise"}, default=None
        Weighting of the simulation error. None: time domain, all samples
        (times ``time_weight`` when given to :meth:`fit`). "relative": time
        domain, each training signal's error relative to its own output
        power, per output, so that records of different amplitude (the
        levels of a test campaign) count alike, as NRMSE scores them; with
        signals of one level the same as None. "band": frequency
        domain, uniform weight on the DFT bins of ``band``. "noise":
        frequency domain, each bin of ``band`` weighted by the inverse noise
        variance of the output, estimated from the spread over the periods
        of each training signal on its own (smoothed over neighbouring bins;
        a signal of one period takes the variance pooled over the others),
        so that the levels of a campaign each count by their own noise
        (needs periodic signals with at least two periods; with ``m``
        outputs the weight is per output, cross-covariances are ignored);
        the fit then runs twice, first in time with each signal relative to
        its power ("relative") and then weighted from that result, because
        the weighted cost stalls when started from the linear model.
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
    stable_at_rest : bool, default=False
        Refuse every optimiser step after which the model, left alone,
        would oscillate by itself (its state equation linearised at rest
        has a spectral radius of 1 or more; the start must not). Why a fit
        goes there, and what refusing costs on the F-16: see
        :class:`~sklearn_pnlss.DecoupledPNLSSRegressor`. False: a fitted
        model unstable at rest is reported by a warning.
    max_iter : int, default=100
        Levenberg-Marquardt iterations at most (of the last stage when the
        degrees grow; each earlier one runs at most ``max_iter // 2``).
    tol : float, default=1e-8
        Stop when an iteration lowers the cost by less than this fraction.
    n_transient : int or "auto", default="auto"
        Samples prepended (periodic signals) or left out of the cost, the
        others simulated from rest (other signals). "auto": the decay time
        of the linear start's slowest pole, at most a period, for periodic
        signals; the other signals start from the state whose simulation
        best reproduces their outputs over that decay time (at most the
        signal), read off again at every evaluation of the cost, and every
        sample counts.
    linear_model : BLAEstimator or None, default=None
        Estimator of the linear start (cloned before fitting); None uses
        ``BLAEstimator(n_states, period=period)``. In a Pipeline after a
        ``BLAEstimator`` stage, that fitted stage is the start instead
        (``make_pipeline(BLAEstimator(3, period=P), PNLSSRegressor(3, period=P))``).
    n_jobs : int or None, default=None
        Threads over the training signals for the simulations and the
        Jacobian (the compiled kernels and the BLAS products release the GIL;
        each thread runs BLAS single-threaded). With fewer signals than
        threads, each non-periodic signal is cut into consecutive pieces,
        every one starting from the state its first samples show (see
        ``n_transient``). Worth it with many signals:
        twenty Bouc-Wen realisations, degrees (3, 5, 7), two cores: 1.2 to
        1.5 times faster per iteration. None means 1, -1 all cores; leave it
        at None inside a parallel grid search.
    verbose : int, default=0
        Print each iteration: cost in dB (rms of the weighted normalised
        error), lambda, and the validation error when validation signals are
        given.
    random_state : int, RandomState instance or None, default=None
        Seeds the new random-phase realisations of the training inputs that
        the fitted model is checked on (see ``fit``); the fit itself is
        deterministic. Pass an int for the same model from every call.

    Attributes
    ----------
    A_, B_, C_, D_, E_, F_ : ndarray
        Model matrices in the user's units.
    model_ : ScaledModel
        The fitted model as one object
        (:class:`~sklearn_pnlss.ScaledModel`): the model in
        normalised units (``model_.normalised``, what Levenberg-Marquardt
        fitted) with the input, output and state scales. It simulates in the
        user's units (``model_.simulate(U, period)``) and gives itself in
        them (``model_.in_user_units()``, from which the attributes below
        are read).
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
        :meth:`fit`); inf where the model diverges on them, or, for an
        iterate better than every earlier one, where it runs away on them
        amplified 1.2 times.
    best_iteration_ : int
        Iteration whose parameters were kept, counted over all stages: the
        last one, or the one best on the validation signals.
    degree_stages_ : list of tuple of int
        The degrees of each stage: one stage with all degrees, or one more
        degree per stage when they grow.
    period_ : int or None
        The period used: ``period``, or the one handed over by the Pipeline
        stage before.
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
        "variables": [Options(str, {"states_inputs", "states"})],
        "equations": [Options(str, {"state", "output", "both"})],
        "grow_degrees": ["boolean", Options(str, {"auto"})],
        "extrapolation": [Options(str, {"hold", "polynomial"})],
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
        stable_at_rest=False,
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
        self.stable_at_rest = stable_at_rest
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

    def _exponents(self, n, m, constant=False):
        # Around an operating point (a linear start with offsets) the even
        # terms shift the mean of the state and the output, which the
        # offsets, the training means, already hold: a constant term in each
        # equation puts it back.
        degrees = self._degrees() + ([0] if constant else [])
        active = np.ones(n + m, dtype=bool)
        if self.variables == "states":
            active[n:] = False
        ex = monomial_exponents(n + m, degrees, active)
        none = np.zeros((0, n + m), dtype=np.int64)
        exE = ex if self.equations in ("state", "both") else none
        exF = ex if self.equations in ("output", "both") else none
        return exE, exF

    def _fit_start(self, stage, X_list, y_list, val, weights):
        """The linear start (the BLA, fitted here or handed over), normalised,
        with every monomial's coefficient zero."""
        self.linear_model_ = self._linear_start(stage, X_list, y_list, self.period_)
        return self._normalised_start(X_list, y_list)

    def _fit_from_start(self, start, objectives, settings, val, X_list):
        """Levenberg-Marquardt on all degrees, or stage by stage on growing
        degrees."""
        self.degree_stages_ = degree_stages(self._degrees(), self.grow_degrees)
        try:
            return optimise_growing_degrees(start, objectives, settings, self.degree_stages_, val)
        except DivergenceError:
            raise ValueError(
                "The linear start diverges on the training data; check the data or give "
                "a stable linear_model."
            ) from None

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

    def _normalised_start(self, X_list, y_list):
        """The linear start with unit-rms inputs, outputs and states, E = F = 0.
        High-degree monomials of order-one variables stay well conditioned."""
        start = self._normalised_linear(self.linear_model_, X_list, y_list)
        linear = start.normalised
        n, p = linear.A.shape[0], linear.C.shape[0]
        constant = bool(np.any(start.input_offset) or np.any(start.output_offset))
        exE, exF = self._exponents(n, linear.B.shape[1], constant)
        return start.with_normalised(replace(
            linear, E=np.zeros((n, exE.shape[0])), F=np.zeros((p, exF.shape[0])), exE=exE, exF=exF,
        ))

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

    def _export(self, X_list):
        user = super()._export(X_list)
        self.E_, self.F_ = user.E, user.F
        self.exponents_E_ = user.exE.copy()
        self.exponents_F_ = user.exF.copy()
        self.trusted_range_ = user.bounds
        return user
