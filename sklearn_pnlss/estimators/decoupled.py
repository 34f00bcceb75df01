"""DecoupledPNLSSRegressor: the PNLSS model with its multivariate polynomial
replaced by a few univariate branches, started by a CPD of the polynomial's
Jacobian tensor and fitted by Levenberg-Marquardt."""
from dataclasses import replace
from numbers import Integral

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import clone
from sklearn.frozen import FrozenEstimator
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from ..decoupling.branches import evaluate_branches
from ..decoupling.start import decoupled_start, random_branches_start
from ..inspection import lm_fit_figures
from ..statespace.degree_growth import chain_stages
from ..statespace.fitting import optimise
from ..statespace.model_base import DivergenceError
from ..utils.handover import attach_stage
from ..utils.parameters import Interval, Options
from ..utils.threads import side_by_side_blas
from ..utils.validation import restore_layout, validate_signals
from ._statespace import FIT_PARAMETER_CONSTRAINTS, StateSpaceRegressorBase
from .bla import BLAEstimator
from .pnlss import PNLSSRegressor

__all__ = ["DecoupledPNLSSRegressor"]


class DecoupledPNLSSRegressor(StateSpaceRegressorBase):
    """Decoupled polynomial nonlinear state-space model.

    ``x(t+1) = A x + B u + W_x g(V^T [x; u])``,
    ``y = C x + D u + W_y g(V^T [x; u])`` (output branches optional), where
    each ``g_l`` is a univariate polynomial of degree ``degree`` (in powers
    or in signed powers, ``branch_basis``), or a cubic spline
    (``n_knots``). It needs ``(2 n + d + 1) r`` nonlinear parameters
    (state equation, ``d`` coefficients per branch) where the full
    polynomial needs them combinatorially many.

    Fitting, ``init="cpd"`` (Fakhrizadeh Esfahani et al., MSSP 2018): a full
    PNLSS model is fitted first (``start_model``, or the one handed over in a
    Pipeline); the Jacobian of its nonlinear part at ``n_points`` points
    drawn from its simulated states and inputs is stacked into a tensor,
    whose rank-r canonical polyadic decomposition gives ``W`` and ``V``; a
    polynomial fit of the branch derivatives, integrated, gives ``g``. If
    that start simulates unstably, it starts from ``W = 0``.
    ``init="random"`` needs no full model, whose coefficients grow with the
    cube of the state count: it starts from the linear model (a
    ``BLAEstimator`` fitted here or handed over) with random branch
    directions over its states and input and ``W = 0``.
    All parameters are then fitted by Levenberg-Marquardt on the simulation
    error with the exact Jacobian (same objective, weighting, transient
    handling and divergence guard as :class:`PNLSSRegressor`). ``n_init``
    starts (other random points, or other random directions) run in
    parallel; the best is kept, by validation error when validation signals
    are given to :meth:`fit`, else by training cost.

    Parameters
    ----------
    n_states : int, default=3
        Model order.
    n_branches : int, default=3
        Number of univariate branches ``r``.
    degree : int, default=10
        Degree ``d`` of each branch (terms of degrees 1 to ``d``; the linear
        term is redundant with A and B and kept only to count parameters as
        the paper does). With ``n_knots``, the degree of the polynomial
        branches the start draws (or the CPD start fits) before it turns
        them into splines: a start from a high degree is steep at the edges
        of the branch range (on a simulated Wiener-Hammerstein system with a
        knee, 10 knots started from random polynomials of degree 3 stay
        below 1 % test error, less than half the error of a polynomial
        branch of degree 12, as many coefficients; started from degree 9,
        near the linear model's plateau, ten times that:
        ``tests/test_spline_branches.py``).
    n_knots : int or None, default=None
        Cubic spline branches on this many evenly spaced knots
        (``n_knots + 2`` coefficients each) instead of polynomials. The
        knots span each branch input's range along the start model's
        simulation, widened by a tenth on each side; beyond them a branch
        follows its edge tangent. For a nonlinearity with a knee (a diode, a
        saturation), which a polynomial follows only at a high degree and
        with ripple. On WH2009 they have not yet done better than
        polynomial branches of degree 21 (see the user guide's decoupling
        page).
    branch_basis : {"powers", "signed_powers"}, default="powers"
        The polynomial branches' terms: ``z ** k``, or the odd signed powers
        ``z |z| ** (k - 1)`` (``k = 1..degree``: ``z``, ``z |z|``, ``z**3``,
        ``z**3 |z|`` ...). Friction, a clearance and hysteresis make a
        structure's stiffness and damping change in proportion to the
        amplitude, which ``z |z|`` gives and a polynomial only approaches
        with many terms (``z**3`` changes them with its square). Measured on
        Bouc-Wen (the seed paper's setting, ``init="random"``, six draws
        of the data): -105.88 dB on the test multisine and -110.13 dB on
        the sweep at the median, against -98.13 dB and -102.06 dB in powers,
        the same 51 nonlinear parameters (``benchmarks/bench_branch_basis.py``).
        Odd branches have no even part (no static offset from the
        nonlinearity): an asymmetric nonlinearity, such as the diode of the
        Wiener-Hammerstein benchmark, is out of their reach, and there they
        stay near the linear model. Not with ``n_knots``.
    period : int or None, default=None
        Samples per period; None: the period of the Pipeline stage this
        model starts from, if any (see :class:`PNLSSRegressor`).
    init : {"cpd", "random"}, default="cpd"
        How the branches start. "cpd": from a full PNLSS model, by the CPD
        of its Jacobian tensor (the paper's method). "random": from the
        linear model, random directions and ``W = 0``: no full model is
        fitted, which is what makes models of many states affordable.
    start_degree : int or None, default=None
        With ``init="random"`` and polynomial branches: fit the branches at
        this lower degree first (a third of ``max_iter``), then at
        ``degree``, the added coefficients starting at zero, for the rest.
        A random start of a high degree often stays on the linear model's
        plateau; grown from a low degree, the branches first capture the
        main nonlinearity. On a Wiener-Hammerstein system with a knee (one
        branch of degree 21, 4 starts) every start grown from degree 7
        leaves the plateau, 1 of 4 started at degree 21; on WH2009 three
        branches grown so reach 0.270 to 0.298 mV on the test record over
        three draws of the starts (see the user guide's decoupling page).
        None: all of ``degree`` from the start.
    n_init : int, default=5
        Starts from different random sampling points and CPD starts
        (``init="cpd"``) or different random directions (``"random"``).
    n_points : int, default=500
        Points at which the Jacobian of the full polynomial is sampled.
    output_branches : bool, default=False
        Let the branches enter the output equation too (``W_y`` fitted); the
        default start then carries an output polynomial as well.
    variables : {"states_inputs", "states"}, default="states_inputs"
        What the branches read, as :class:`PNLSSRegressor`'s ``variables``:
        ``[x; u]``, or the states alone (the input rows of ``V_`` held at
        zero; the default full start is then a polynomial in the states,
        and a start given with the input in its polynomial has the input
        rows of its decomposition dropped), when the physics says the input
        enters linearly: a pump's flow into a tank, a force on a drive. On the cascaded tanks (two states, two
        cubic branches in both equations, ``init="random"``) nine draws of
        its five random starts reach 0.331 to 0.333 V on the test record
        with the states alone, and 0.342 to 0.924 V with the input in the
        branches too (``benchmarks/bench_field.py``).
    start_model : PNLSSRegressor, FrozenEstimator or None, default=None
        The full model to start from (``init="cpd"`` only): a
        ``PNLSSRegressor`` is cloned and fitted on the signals given to
        ``fit``; a fitted one wrapped in
        :class:`sklearn.frozen.FrozenEstimator` is used as it is (not
        refitted: a large full model fitted once serves every decoupled
        model tried from it). None uses ``PNLSSRegressor(n_states,
        degrees=(2, 3), variables="states_inputs", period=period)`` (the
        paper's start). In a Pipeline after a fitted ``PNLSSRegressor``
        stage, that stage is the start instead.
    extrapolation : {"hold", "linear", "polynomial"}, default="hold"
        What each branch does where its input leaves the range it covered in
        training (``z_range_``, widened by ``range_margin``). "hold": the
        branch keeps its edge value, so the nonlinear term is bounded and a
        stable ``A`` gives a bounded state for every bounded input: the
        model cannot run away on a new signal of the training kind and level
        (bounded by construction). "linear": continued along its edge
        tangent (continuous derivative, no such guarantee; -92.22 dB where
        "hold" gives -93.35 dB, see ``range_margin``). "polynomial": the
        plain polynomial everywhere. Inside the range nothing changes.
    range_margin : float, default=0.0
        Widening of each branch's trusted range on each side, as a fraction
        of its width. Measured on Bouc-Wen (3 branches of degree 10, the main
        job's model, its simulated 55 N test multisine;
        ``benchmarks/bench_branch_margins.py``): 0 gives -93.35 dB, 0.02
        -93.45 dB, 0.1 -26.97 dB (a fit that fails on the test signal), and
        the plain polynomial -91.01 dB; high-degree branches are steep at
        their edges, so the default trusts only the range the data covered.
    stable_at_rest : bool, default=False
        Refuse every optimiser step that makes the model unstable at rest
        (its state equation linearised at ``x = 0``, ``u = 0``, branch or
        monomial slopes there included, with a spectral radius of 1 or
        more), as one whose simulation diverges is refused; the start must
        be stable at rest. Such a model oscillates by itself under no input
        or one below the levels it was fitted at, which no passive
        structure does; a fit may go there to shape a damping that grows
        with the amplitude. Measured on the F-16 (18 states, three branches
        of degree 5 in signed powers, ``benchmarks/f16_error_budget.py``):
        two of three draws end unstable at rest, one ringing with no force
        at about a tenth of its level-1 response; refused, their mean test
        NRMSE goes from 0.151 and 0.160 to 0.172 and 0.165 (the draw stable
        at rest is unchanged). False: a fitted model unstable at rest is
        reported by a warning.
    average_periods, weighting, band, max_iter, tol, n_transient
        As in :class:`PNLSSRegressor`, for the decoupled model's fit.
    n_jobs : int or None, default=None
        Parallel starts (joblib threads: the compiled kernels release the
        GIL; BLAS on one thread while several run at once). None means 1.
    verbose : int, default=0
        Print the iterations of each start.
    random_state : int, RandomState instance or None, default=None
        Seeds the sampling points and CPD starts of the ``n_init`` starts,
        and the new random-phase realisations of the training inputs that
        the fitted model is checked on (see ``fit``).

    Attributes
    ----------
    A_, B_, C_, D_ : ndarray
        Linear part in the user's units.
    model_ : ScaledModel
        The fitted model as one object (see :class:`PNLSSRegressor`).
    V_ : ndarray of shape (n_states + n_inputs, n_branches)
        Branch directions over ``[x; u]`` in the user's units.
    W_x_ : ndarray of shape (n_states, n_branches)
    W_y_ : ndarray of shape (n_outputs, n_branches)
        Zero without output branches.
    coef_ : ndarray of shape (n_branches, degree) or (n_branches, n_knots + 2)
        ``coef_[l, k]`` multiplies ``z_l ** (k + 1)`` in ``g_l`` (``z_l
        |z_l| ** k`` with ``branch_basis="signed_powers"``); for spline
        branches, the ``k``-th cubic B-spline less its value at 0.
    branch_knots_ : ndarray of shape (n_branches, n_knots) or None
        The knots of each spline branch, in the units of ``z``; None for
        polynomial branches.
    z_range_ : ndarray of shape (n_branches, 2)
        Range of each branch input ``z_l = V_[:, l] @ [x; u]`` on the
        training data (where the branches are trustworthy).
    trusted_range_ : ndarray of shape (n_branches, 2)
        Range of each branch input inside which the branch is the fitted
        polynomial (see ``extrapolation``); infinite with
        ``extrapolation="polynomial"``.
    start_model_ : PNLSSRegressor or BLAEstimator
        The fitted model the decoupled model started from: the full model
        (``init="cpd"``) or the linear one (``"random"``).
    cpd_errors_ : ndarray of shape (n_init,)
        Relative CPD error of each start (NaN with ``init="random"``).
    init_scores_ : ndarray of shape (n_init,)
        Validation rms error in dB (or training cost in dB) of each start
        after fitting; the lowest was kept (``best_init_``).
    n_params_, n_nonlinear_params_, n_iter_, best_iteration_ : int
    cost_history_, validation_history_ : ndarray
        Of the kept start (see :class:`PNLSSRegressor`).
    period_ : int or None
        The period used (see :class:`PNLSSRegressor`).
    n_features_in_, n_outputs_ : int

    Examples
    --------
    >>> from sklearn_pnlss import DecoupledPNLSSRegressor
    >>> DecoupledPNLSSRegressor(n_branches=3, degree=10).get_params()["n_init"]
    5
    """

    _parameter_constraints = {
        **FIT_PARAMETER_CONSTRAINTS,
        "n_states": [Interval(Integral, 1, None, closed="left")],
        "n_branches": [Interval(Integral, 1, None, closed="left")],
        "degree": [Interval(Integral, 2, None, closed="left")],
        "n_knots": [Interval(Integral, 2, None, closed="left"), None],
        "branch_basis": [Options(str, {"powers", "signed_powers"})],
        "init": [Options(str, {"cpd", "random"})],
        "start_degree": [Interval(Integral, 2, None, closed="left"), None],
        "n_init": [Interval(Integral, 1, None, closed="left")],
        "n_points": [Interval(Integral, 2, None, closed="left")],
        "output_branches": ["boolean"],
        "variables": [Options(str, {"states_inputs", "states"})],
        "start_model": [None, PNLSSRegressor, FrozenEstimator],
        "extrapolation": [Options(str, {"hold", "linear", "polynomial"})],
        "n_jobs": [Integral, None],
    }

    def __init__(
        self,
        n_states=3,
        *,
        n_branches=3,
        degree=10,
        n_knots=None,
        branch_basis="powers",
        period=None,
        init="cpd",
        start_degree=None,
        n_init=5,
        n_points=500,
        output_branches=False,
        variables="states_inputs",
        start_model=None,
        extrapolation="hold",
        range_margin=0.0,
        stable_at_rest=False,
        average_periods=True,
        weighting=None,
        band=None,
        max_iter=100,
        tol=1e-8,
        n_transient="auto",
        n_jobs=None,
        verbose=0,
        random_state=None,
    ):
        self.n_states = n_states
        self.n_branches = n_branches
        self.degree = degree
        self.n_knots = n_knots
        self.branch_basis = branch_basis
        self.period = period
        self.init = init
        self.start_degree = start_degree
        self.n_init = n_init
        self.n_points = n_points
        self.output_branches = output_branches
        self.variables = variables
        self.start_model = start_model
        self.extrapolation = extrapolation
        self.range_margin = range_margin
        self.stable_at_rest = stable_at_rest
        self.average_periods = average_periods
        self.weighting = weighting
        self.band = band
        self.max_iter = max_iter
        self.tol = tol
        self.n_transient = n_transient
        self.n_jobs = n_jobs
        self.verbose = verbose
        self.random_state = random_state

    def _fit_start(self, stage, X_list, y_list, val, weights):
        """The fitted model the decoupled starts are drawn from in
        ``_fit_from_start`` (``start_model_``, handed over or fitted here):
        the full PNLSS model, or the linear one for ``init="random"``."""
        if self.start_degree is not None and (self.init != "random" or self.n_knots is not None
                                              or self.start_degree >= self.degree):
            raise ValueError(
                f"start_degree={self.start_degree} grows polynomial branches from a random start to a higher "
                f"degree: it needs init='random', n_knots=None and start_degree < degree={self.degree} "
                f"(got init={self.init!r}, n_knots={self.n_knots}); or leave start_degree None."
            )
        if self.n_knots is not None and self.branch_basis != "powers":
            raise ValueError(
                f"branch_basis={self.branch_basis!r} is a polynomial basis, but n_knots={self.n_knots} asks for "
                "spline branches; leave n_knots None or branch_basis='powers'."
            )
        if self.init == "random":
            if self.start_model is not None:
                raise ValueError(
                    "start_model is the full model of init='cpd'; init='random' starts from the linear "
                    "model: leave start_model None (or use init='cpd')."
                )
            self.start_model_ = self._linear_start(stage, X_list, y_list)
            return self._normalised_linear(self.start_model_, X_list, y_list)
        self.start_model_ = self._start_model(stage, X_list, y_list, val, weights)
        return self.start_model_.model_

    def _fit_from_start(self, full, objectives, settings, val, X_list):
        """``n_init`` decoupled starts drawn along the start model's
        simulation of ``X_list`` (CPDs of the full model's Jacobian tensor,
        or random branches on the linear model), fitted in parallel; the
        best is kept."""
        trajectory = self._trajectory(full, X_list, "start model")
        seeds = check_random_state(self.random_state).randint(np.iinfo(np.int32).max, size=self.n_init)
        with side_by_side_blas(self.n_jobs, len(seeds)):
            runs = Parallel(n_jobs=self.n_jobs, prefer="threads")(
                delayed(self._one_start)(full, trajectory, int(seed), objectives, settings, val) for seed in seeds
            )
        fits, cpd_errors = zip(*runs)
        scores = np.array([
            f.validation_error if val is not None else 10 * np.log10(f.kept_cost) for f in fits
        ])
        self.best_init_ = int(np.argmin(scores))
        self.init_scores_ = scores
        self.cpd_errors_ = np.array(cpd_errors)
        return fits[self.best_init_]

    def _linear_start(self, stage, X_list, y_list):
        """The fitted BLA handed over by the previous Pipeline stage, or one
        fitted here (``init="random"``)."""
        if stage is None:
            return BLAEstimator(self.n_states, period=self.period_).fit(X_list, y_list)
        if not isinstance(stage, BLAEstimator):
            raise TypeError(
                "DecoupledPNLSSRegressor(init='random') starts from the linear model: the previous "
                f"Pipeline stage must be a BLAEstimator, not a {type(stage).__name__} (init='cpd' starts "
                "from a PNLSSRegressor)."
            )
        if stage.n_states != self.n_states:
            raise ValueError(
                f"The linear model has n_states={stage.n_states} but n_states={self.n_states}; make them equal."
            )
        return stage

    def _trajectory(self, model, X_list, what):
        """Normalised ``[x; u]`` along the simulation of the training inputs
        by ``model`` (a ScaledModel), in periodic steady state, or from rest
        when the steady-state iteration diverges."""
        for per in dict.fromkeys((self.period_, None)):
            try:
                return model.normalised_trajectory(X_list, per)
            except DivergenceError:
                continue
        raise ValueError(
            f"The {what} diverges when simulated on the training signals X; lower "
            "max_iter, pass validation signals (X_val, y_val), or check the data."
        )

    def _start_model(self, stage, X_list, y_list, val, weights):
        """The fitted full PNLSS model the decoupled one starts from."""
        if isinstance(stage, PNLSSRegressor):
            start = stage
        else:
            if stage is not None and not isinstance(stage, BLAEstimator):
                raise TypeError(
                    "DecoupledPNLSSRegressor starts from a PNLSSRegressor (or BLAEstimator) stage; "
                    f"the previous Pipeline stage is a {type(stage).__name__}."
                )
            if isinstance(self.start_model, FrozenEstimator):
                start = self._frozen_start(X_list)
            else:
                start = clone(self.start_model) if self.start_model is not None else PNLSSRegressor(
                    self.n_states, degrees=(2, 3), variables=self.variables,
                    equations="both" if self.output_branches else "state", period=self.period_,
                    random_state=self.random_state,
                )
                X_fit = X_list if stage is None else attach_stage(X_list, stage)
                X_val, y_val = val if val is not None else (None, None)
                start.fit(X_fit, y_list, X_val=X_val, y_val=y_val, time_weight=weights)
        if start.n_states != self.n_states:
            raise ValueError(
                f"The start model has n_states={start.n_states} but n_states={self.n_states}; make them equal."
            )
        return start

    def _frozen_start(self, X_list):
        """The fitted full model ``start_model`` wraps, as it is."""
        start = self.start_model.estimator
        if not isinstance(start, PNLSSRegressor):
            raise TypeError(
                f"start_model wraps a {type(start).__name__}; the full model to start from is a fitted "
                "PNLSSRegressor: FrozenEstimator(PNLSSRegressor(...).fit(X, y))."
            )
        check_is_fitted(start, "model_", msg="start_model wraps a PNLSSRegressor that is not fitted; fit it "
                        "before wrapping it in FrozenEstimator, or pass it unwrapped to have it fitted here.")
        if X_list[0].shape[1] != start.n_features_in_:
            raise ValueError(
                f"X has {X_list[0].shape[1]} input channel(s) but the frozen start_model was fitted on "
                f"{start.n_features_in_}; fit the decoupled model on signals of the start model's inputs."
            )
        return start

    def _one_start(self, full, trajectory, seed, objectives, settings, val):
        if self.init == "random":
            model = random_branches_start(full.normalised, trajectory, self.n_branches,
                                          self.start_degree or self.degree, n_knots=self.n_knots,
                                          signed=self._signed, input_directions=self._input_directions,
                                          random_state=seed)
            model.output_branches = bool(self.output_branches)
            if self.start_degree is None:
                return optimise(full.with_normalised(model), objectives, settings, val), np.nan
            return self._grown(full.with_normalised(model), objectives, settings, val), np.nan
        model, cpd_error = decoupled_start(
            full.normalised, trajectory, self.n_branches, self.degree, n_points=self.n_points,
            n_knots=self.n_knots, signed=self._signed, random_state=seed,
        )
        model = model.with_theta(model.theta)  # a private copy
        model.output_branches = bool(self.output_branches)
        if not self._input_directions:  # the decomposition's directions over the states alone
            model.V[self.n_states :] = 0.0
            model.input_directions = False
        if not self.output_branches:
            model.Wy[:] = 0.0
        try:
            return optimise(full.with_normalised(model), objectives, settings, val), cpd_error
        except DivergenceError:
            # The paper's step 7: an unstable start is replaced by W = 0
            # (the linear model), from which LM grows the branches.
            model.Wx[:] = 0.0
            model.Wy[:] = 0.0
            return optimise(full.with_normalised(model), objectives, settings, val), cpd_error

    @property
    def _signed(self):
        return self.branch_basis == "signed_powers"

    @property
    def _input_directions(self):
        return self.variables == "states_inputs"

    def _grown(self, start, objectives, settings, val):
        """Branches of ``start_degree`` fitted for a third of ``max_iter``,
        then raised to ``degree`` (zero coefficients) and fitted for the
        rest; one fit whose iterations run on across both stages."""
        first = optimise(start, objectives, settings, val, max_iter=self.max_iter // 3)
        fitted = first.model.normalised
        # unbounded again, as the start was: the trusted range is read off
        # the final model's trajectory (held at the first stage's range,
        # the branches would change when it is read again)
        raised = replace(fitted, G=np.hstack([fitted.G, np.zeros((fitted.n_branches, self.degree - fitted.degree))]),
                         bounds=None, linear_extrapolation=False)
        second = optimise(first.model.with_normalised(raised), objectives, settings, val,
                          max_iter=self.max_iter - self.max_iter // 3)
        return chain_stages([first, second])

    def _export(self, X_list):
        user = super()._export(X_list)
        self.V_, self.W_x_, self.W_y_ = user.V, user.Wx, user.Wy
        self.coef_ = user.G
        self.branch_knots_ = None if user.knots is None else (
            user.knots[:, :1] + np.arange(user.G.shape[1] - 2) * user.knots[:, 1:])
        # The branch inputs' range along the fitted model's own simulation
        # (after LM its state basis is no longer the start's).
        z = self._trajectory(self.model_, X_list, "fitted decoupled model") @ self.model_.normalised.V
        self.z_range_ = np.column_stack([z.min(axis=0), z.max(axis=0)])
        self.trusted_range_ = user.bounds
        return user

    def _summary_structure(self):
        return {
            "branches": int(self.coef_.shape[0]),
            **({"knots": int(self.branch_knots_.shape[1])} if self.branch_knots_ is not None
               else {"degree": int(self.coef_.shape[1]), "basis": self.branch_basis}),
            "output_branches": bool(self.output_branches),
            "branch_input_ranges": [f"[{lo:.3g}, {hi:.3g}]" for lo, hi in self.z_range_],
        }

    def _summary_fit(self):
        fit = lm_fit_figures(self)
        fit["starts"] = int(self.init_scores_.size)
        fit["kept_start"] = int(self.best_init_)
        fit["start_scores_db"] = [float(v) for v in self.init_scores_]
        fit["cpd_errors"] = [float(v) for v in self.cpd_errors_]
        return fit

    def branch_inputs(self, X):
        """The branch inputs ``z = V_^T [x; u]`` along the model's simulation
        of ``X``: where the branches are evaluated (for plots, and to see
        whether new signals stay inside ``z_range_``).

        Parameters
        ----------
        X : signals, as in :meth:`predict`
            Periodic signals (with ``period`` set) are simulated in steady
            state, the others from rest.

        Returns
        -------
        z : signals in the layout of ``X`` with ``n_branches`` channels
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        out = []
        for U in X_list:
            period = self.period_ if self._signal_is_periodic(U.shape[0]) else None
            try:
                s = self.model_.normalised_trajectory([U], period)
            except DivergenceError as exc:
                raise ValueError(f"{type(self).__name__}.branch_inputs: {exc}; X drives the model far "
                                 "outside the range it was fitted on.") from None
            # Both in normalised units: V_ absorbed the scaling, z is the same.
            out.append(s @ self.model_.normalised.V)
        return restore_layout(out, layout)

    def branch_values(self, z=None, n_points=200):
        """Each branch ``g_l`` evaluated on a grid (for plots and
        interpretation), as the model evaluates it: outside its trusted
        range (``trusted_range_``) continued as ``extrapolation`` says.

        Parameters
        ----------
        z : array-like of shape (n_z,) or (n_z, n_branches) or None
            Branch inputs; None: ``n_points`` values spanning each branch's
            training range ``z_range_``.
        n_points : int, default=200

        Returns
        -------
        z : ndarray of shape (n_z, n_branches)
        g : ndarray of shape (n_z, n_branches)
        """
        check_is_fitted(self)
        if z is None:
            lo, hi = self.z_range_[:, 0], self.z_range_[:, 1]
            z = lo + np.linspace(0.0, 1.0, n_points)[:, None] * (hi - lo)
        z = np.asarray(z, dtype=float)
        if z.ndim == 1:
            z = np.repeat(z[:, None], self.coef_.shape[0], axis=1)
        model = self.model_.normalised
        return z, evaluate_branches(self.coef_, z, model.bounds, model.linear_extrapolation, model.knots,
                                    model.signed)
