"""The response above the excited band, switched on by the model's state.

A structure with a joint that knocks (clearance, stick-slip) answers a
band-limited excitation with content far above the band: each impact rings
the structure's higher modes. A state-space model identified from the
band (its linear start is the BLA at the excited lines) has nothing there,
however good it is inside the band. On the F-16 ground vibration test this
content is a floor: a model perfect in 2-15 Hz would still miss the test
levels by 0.132 NRMSE (mean over the outputs and levels 2, 4, 6).

The content is not noise (it repeats period after period) and it is not a
linear response to the shaker force either: from the F-16's test level 2
to level 6 the force's content above the band grows 32-fold, the
accelerations' there 304- to 7415-fold. But the measured force holds the
impacts' timing, since the shaker feels them, and the model's state says
when the joint is in the knocking regime. So the out-of-band output is
modelled as the force's out-of-band content, gated by a function of the
state, through FIR filters (the higher modes' ringing):

    y_above(t) = sum_j h_j g(x(t - j)) u_above(t - j),

with ``g(x) = max(q(x), 0)`` and ``q`` a quadratic form of the state fitted
to the amplitude envelope of the out-of-band residual (where the impacts
are: the square root of its power averaged over a cycle of the cutoff), and
the ``h_j`` fitted by ridge regression on that residual. Both fits are
linear least squares on top of the fitted state-space model.

How an impact rings the structure depends on how hard and in which phase
of the motion the joint knocks, which no sum of the gated force's delays
holds: with ``hidden_units``, a one-hidden-layer network on a window of the
model's in-band prediction and the gated force takes the FIR's place. With
``in_band`` it reads the input in the band as well and models the model's
whole error: what the state-space model leaves in the band, a map of its
own simulation and the input corrects.

Where the force does not show the impacts (the shaker far from the joint),
the simulated motion does: with ``clearances``, the hinges of the model's
in-band velocities past a clearance, gated like the input and kept above
the cutoff, are more inputs of the FIR filters. Each kink rings the modes above the band, at
the time the motion opens the contact.
"""
from numbers import Integral, Real
from typing import NamedTuple

import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.model_selection import BaseCrossValidator, BaseShuffleSplit, LeaveOneOut, check_cv
from sklearn.utils.validation import check_is_fitted

from ..utils.parameters import Interval, validates_parameters
from ..utils.validation import restore_layout, signal_layout, validate_signals
from ._base import DynamicRegressorMixin
from ._gated import (FirRidge, above_cutoff, apply_fir, channel_rms, envelope, fit_gate, gate, hinges,
                     integral_in_band, relative_motions)
from ._window_network import apply_networks, fit_networks, held_out_rows, windows
from .bla import BLAEstimator

__all__ = ["AboveBandRegressor"]


def quadratic_features(x):
    """``[1, x_i x_j (i <= j)]`` of each sample of ``x`` (n_samples, n)."""
    i, j = np.triu_indices(x.shape[1])
    return np.hstack([np.ones((x.shape[0], 1)), x[:, i] * x[:, j]])


class _Signal(NamedTuple):
    """One input signal as the model sees it: the regressor's prediction,
    its states (normalised units), the input's content above and below the
    cutoff, and its period when it is periodic (steady state, circular
    FIRs), else None."""

    prediction: np.ndarray
    states: np.ndarray
    input_above: np.ndarray
    input_below: np.ndarray
    period: int | None

    @property
    def periodic(self):
        return self.period is not None


def state_space_steps(regressor):
    """The steps of a fitted regressor that simulate states: its own, a
    Pipeline's last, or each member's of an :class:`AveragedRegressor`
    (the members side by side are the mean's state-space model)."""
    members = getattr(regressor, "estimators_", None)
    steps = [r.steps[-1][1] if hasattr(r, "steps") else r for r in (members or [regressor])]
    for step in steps:
        if not hasattr(getattr(step, "model_", None), "normalised_trajectory"):
            raise TypeError(
                f"regressor: {type(step).__name__} has no state-space model to gate with; pass one of the "
                "library's regressors (BLAEstimator, PNLSSRegressor, DecoupledPNLSSRegressor), a Pipeline "
                "ending in one, or an AveragedRegressor of them."
            )
    return steps


def state_space_n_params(regressor):
    """The parameters of a fitted regressor's state-space models."""
    return int(sum(step.n_params_ for step in state_space_steps(regressor)))


def simulated(regressor, U):
    """A fitted regressor's steps that simulate states, the period it
    simulates ``U`` with (None: from rest) and its simulation of ``U``
    (n_samples, n_outputs)."""
    steps = state_space_steps(regressor)
    period = steps[0]._period() if steps[0]._signal_is_periodic(U.shape[0]) else None
    return steps, period, np.asarray(regressor.predict(U)).reshape(U.shape[0], -1)


def model_signal(regressor, U, cutoff, fs):
    """One input signal ``U`` as a fitted regressor sees it (see
    ``_Signal``): its simulation and states (each member's side by side),
    the input split at ``cutoff``."""
    steps, period, prediction = simulated(regressor, U)
    states = np.hstack([step.model_.normalised_trajectory([U], period)[:, :-U.shape[1]] for step in steps])
    input_above = above_cutoff(U, cutoff, fs)
    return _Signal(prediction, states, input_above, U - input_above, period)


def fit_state_gate(signals, residuals, cutoff, fs):
    """The gate of ``signals`` (``_Signal``) on the regressor's errors above
    ``cutoff`` (``residuals``): the errors' rms per output, the states' rms
    (the gate's units) and the coefficients of ``q``, fitted to the errors'
    envelope (in units of their rms) over one period of the cutoff
    frequency."""
    above_band_rms = np.sqrt(np.mean(np.vstack(residuals) ** 2, axis=0))
    state_scale = channel_rms([s.states for s in signals])
    window = max(1, int(round(fs / cutoff)))
    envelopes = [envelope(r, above_band_rms, window, s.periodic) for s, r in zip(signals, residuals)]
    coef = fit_gate([s.states for s in signals], envelopes, lambda x: quadratic_features(x / state_scale))
    return above_band_rms, state_scale, coef


def gated_input(signal, state_scale, coef, cutoff, fs):
    """The input of ``signal`` above ``cutoff``, switched on by the gate
    (``fit_state_gate``) of its states, and kept above ``cutoff``."""
    return above_cutoff(gate(signal.states / state_scale, coef)[:, None] * signal.input_above, cutoff, fs)


def check_cutoff(estimator, y):
    """The checks of a model above the band before its fit: a target, and a
    ``cutoff`` below the Nyquist frequency."""
    if y is None:
        raise ValueError(f"{type(estimator).__name__} requires y to be passed, but the target y is None.")
    if estimator.cutoff is None:
        raise ValueError("cutoff: pass the highest frequency the input excites (in the units of fs); "
                         "the content above it is what this model adds.")
    if estimator.cutoff >= estimator.fs / 2:
        raise ValueError(f"cutoff={estimator.cutoff} is at or above the Nyquist frequency fs / 2 = "
                         f"{estimator.fs / 2}; nothing lies above it. Pass a cutoff below fs / 2.")


class AboveBandRegressor(DynamicRegressorMixin, BaseEstimator):
    """A state-space model plus its response above the excited band.

    ``regressor`` is fitted as usual; the part of its simulation error above
    ``cutoff`` is then modelled as the input's own content above ``cutoff``,
    switched on by a gate the model's state sets, through FIR filters:
    ``y_above(t) = sum_j h_j g(x(t - j)) u_above(t - j)``, ``g(x) =
    max(q(x), 0)`` with ``q`` quadratic in the state. For structures whose
    joints knock: the impacts ring modes above the excitation band, the
    measured force holds their timing (the shaker feels them), the state
    says when the joint knocks. Both extra fits are linear least squares.

    Parameters
    ----------
    regressor : estimator or None, default=None
        One of the library's regressors, a Pipeline ending in one, or an
        :class:`AveragedRegressor` of them (its states set the gate; an
        average's are its members' side by side); None fits
        ``BLAEstimator()``. Cloned at fit; wrap a fitted model in
        :class:`sklearn.frozen.FrozenEstimator` to keep it as it is.
    cutoff : float or None, default=None
        The highest frequency the input excites, in the units of ``fs``:
        the content above it is modelled. Required.
    fs : float, default=1.0
        Sampling frequency (1.0: ``cutoff`` in cycles per sample).
    n_taps : int, default=200
        Length of each FIR filter in samples: as long as the higher modes
        ring (0.5 s at the F-16's 400 Hz).
    n_lead : int, default=0
        How many of the taps reach ahead: ``y_above(t) = sum_j h_j w(t +
        n_lead - j)`` for the gated input ``w``. 0 keeps the model causal.
        A measured force can show an impact later than a sensor nearer the
        joint does (the shaker feels the structure's ringing as it builds
        up); a lead lets the filters read it there, and makes the model a
        map of the whole measured record rather than a simulator: the
        prediction at t uses the input up to ``n_lead`` samples after t.
        Below ``n_taps``.
    alpha : float or array-like of float, default=1e-4
        Ridge penalty of the FIR fit, relative to the mean diagonal of its
        normal matrix; with ``hidden_units``, the network's L2 penalty on its
        weights (in units of its standardised inputs and outputs). Several
        values (FIR filters only): the one whose filters, fitted without
        them, simulate the held-out training signals of ``cv`` best is kept
        (``alpha_``). The regressor, the gate and the hinges' scales are
        fitted once on every signal; only the filters are held out, from
        correlations computed once: each candidate and split costs one
        Cholesky solve.
    cv : int, splitter, list of (train, test) or None, default=None
        With several ``alpha``: how the training signals are held out.
        None: each signal in turn; an int ``k``: ``k`` contiguous groups of
        signals (:class:`~sklearn.model_selection.KFold`); a splitter
        without groups, or a list of ``(train, test)`` arrays of signal
        indices (hold out what a new test will be: another level, another
        waveform).
        Whole signals are split, never samples within one.
    clearances : tuple of float or None, default=None
        With the FIR filters: the contacts that open past a clearance, as
        more inputs of the filters beside the gated input. The outputs'
        content in the band, as the regressor simulates it, is integrated
        ``n_integrations`` times (velocities for accelerometers), and each
        output and each difference of two (a joint between two sensors moves
        by their difference) gives ``max(m - c, 0)`` and ``min(m + c, 0)``
        for each clearance ``c``, in units of that motion's largest rms over
        the training signals, switched on by the same gate as the input (the
        motion says when a contact opens, the gate whether the joint knocks
        at that amplitude). The kinks ring the modes above the band as an
        impact does, at the time the simulated motion says. Train on more
        than one waveform (multisines and sine sweeps): the filters then
        learn the contacts, not one record's timing. ``n_outputs * (n_outputs
        + 1)`` channels per clearance, each ``n_taps`` coefficients per
        output.
    n_integrations : int, default=1
        With ``clearances``: how many times the outputs are integrated in
        time before the hinges (1: the velocities of accelerometers; 0: the
        outputs themselves). Content below a sixteenth of ``cutoff`` is
        dropped first, as integrating magnifies it.
    hidden_units : int or None, default=None
        None: the FIR filters above, linear in the gated input. An int: a
        network with that many rectified units in one hidden layer takes
        their place. It reads a window of the regressor's prediction below
        ``cutoff`` and of the gated input (every ``window_stride``-th of the
        last ``n_taps`` samples) and gives the output above ``cutoff`` at the
        window's newest sample. Each training signal counts relative to its
        own output power, as the NRMSE scores it. The fit stops where the
        network does worst on windows it has not seen: the last tenth of
        every period (of the signal when it is not periodic), held out. A
        random tenth of the windows would not tell, each window being nearly
        its neighbour; the periods of a periodic signal repeat one input, so
        past that point the network learns its waveform by heart. About
        ``(n_outputs + n_inputs) * n_taps / window_stride * hidden_units``
        weights.
    in_band : bool, default=False
        With ``hidden_units``: the network models the regressor's error in
        the band as well, reading the input below ``cutoff`` beside its
        window. What the state-space model leaves in the band (a distortion
        its polynomial does not hold, its fit's compromise between the
        training levels) is then corrected by a map of its own simulation and
        the input: the model stays a simulator of a new input.
    window_stride : int, default=2
        With ``hidden_units``: the window holds every ``window_stride``-th
        sample.
    n_networks : int, default=1
        With ``hidden_units``: so many networks, fitted from different
        initial weights, are averaged (their errors partly cancel), for as
        many times the weights and the fitting time.
    n_jobs : int or None, default=None
        With ``n_networks`` above 1: how many networks are fitted at a time
        (joblib's convention: None one, -1 as many as there are cores).
    random_state : int, RandomState instance or None, default=None
        With ``hidden_units``: the networks' initial weights and the order
        of their training windows (an int seeds the k-th
        network with ``random_state + k``; otherwise each network's seed is
        drawn from it). An int makes the fit reproducible, whatever
        ``n_jobs``.

    Attributes
    ----------
    regressor_ : estimator
        The fitted state-space model.
    alpha_ : float
        The ridge penalty the filters or the network are fitted with:
        ``alpha``, or with several the one ``cv`` chose.
    cv_nrmse_ : ndarray of shape (n_alphas,)
        With several ``alpha``: the NRMSE of the whole simulation (the
        regressor's and the map's) of the held-out signals, averaged over
        the outputs and each split's held-out signals, then over the
        splits, for each ``alpha``.
    state_scale_ : ndarray of shape (n_states,)
        The rms of each state on the training signals (the gate's units).
    gate_coef_ : ndarray of shape (1 + n_states * (n_states + 1) // 2,)
        Coefficients of ``q``: a constant, then ``x_i x_j`` (``i <= j``, as
        :func:`numpy.triu_indices` orders them) of the scaled states.
    fir_ : ndarray of shape (n_inputs, n_taps, n_outputs)
        ``fir_[i, j, k]``: from the gated input ``i`` delayed ``j - n_lead``
        samples to output ``k``; with ``clearances``, the inputs after the
        gated ones are the hinges. Only without ``hidden_units``.
    motion_scale_ : ndarray of shape (n_outputs * (n_outputs + 1) // 2,)
        The largest rms over the training signals of each output's motion
        and each difference of two (the clearances' unit). Only with
        ``clearances``.
    hinge_scale_ : float
        The hinges' common scale in the filters' inputs (their rms over the
        training signals over the gated input's), so that the ridge penalty
        weighs both alike. Only with ``clearances``.
    networks_ : list of sklearn.neural_network.MLPRegressor
        The fitted networks, in units of their standardised inputs and
        outputs. Only with ``hidden_units``.
    network_input_scale_, network_output_scale_ : ndarray
        The standard deviation of each window column on the training signals,
        and the rms of the training error above ``cutoff`` (all of it with
        ``in_band``) per output: the network's units.
        Only with ``hidden_units``.
    n_map_params_ : int
        The coefficients of the gate and of the FIR filters or the network.
    n_params_ : int
        The state-space model's parameters and ``n_map_params_``.
    above_band_rms_ : ndarray of shape (n_outputs,)
        The rms of the regressor's training error above ``cutoff``.
    explained_fraction_ : ndarray of shape (n_outputs,)
        The share of that error's power (of the whole error with
        ``in_band``) the map explains on the training signals.
    n_features_in_, n_outputs_ : int

    Notes
    -----
    Measured on the F-16 ground vibration test (``benchmarks/bench_f16.py``
    ``--above-band``): every decoupled model of the protocol loses about
    0.02 of its mean test NRMSE (the selected one 0.182 to 0.162), all of it
    on the levels where the joint knocks; the lowest test level, where it
    does not, keeps its figures.
    With ``hidden_units=128`` and ``in_band=True`` (``--in-band``, an
    18-state model, three draws of its starts) one network takes 0.023 to
    0.027 off the model's mean (0.179 to 0.155 on the first draw), and 0.011
    to 0.013 off its mean on the test levels' sine sweeps, a waveform the
    fit never saw: there, no more than the gated FIRs.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sklearn_pnlss import AboveBandRegressor, BLAEstimator
    >>> from sklearn_pnlss.metrics import nrmse_by_band
    >>> rng = np.random.default_rng(0)
    >>> def fast(u):  # the content of u above 0.1 cycles per sample
    ...     U = np.fft.rfft(u)
    ...     U[np.fft.rfftfreq(u.size) <= 0.1] = 0
    ...     return np.fft.irfft(U, u.size)
    >>> def record(n=8192):  # a slow force with some fast content; a rattle at large motion
    ...     u = lfilter([0.1], [1, -0.9], rng.standard_normal(n)) + 0.05 * rng.standard_normal(n)
    ...     y = lfilter([0.0, 0.1], [1, -0.9], u)
    ...     knock = np.maximum(y**2 - 2 * np.var(y), 0) * fast(u)
    ...     return u[:, None], (y + lfilter([0.0, 1.0], [1, 0.5], knock))[:, None]
    >>> (u, y), (u_new, y_new) = record(), record()
    >>> model = AboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, n_taps=8).fit(u, y)
    >>> alone = BLAEstimator(2, fs=1.0).fit(u, y)
    >>> def error_above(m):  # NRMSE of the new record above the cutoff
    ...     return float(nrmse_by_band(y_new, m.predict(u_new), fs=1.0, edges=(0.1, 0.51))[0, 0])
    >>> round(error_above(alone), 4), round(error_above(model), 4)
    (0.011, 0.008)
    >>> u_2, y_2 = record()  # with a second record, the ridge chosen holding each out in turn
    >>> chosen = AboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, n_taps=8, alpha=(1e-4, 1e-1, 10.0))
    >>> chosen.fit([u, u_2], [y, y_2]).alpha_, chosen.cv_nrmse_.round(4).tolist()
    (0.0001, [0.0099, 0.01, 0.0134])
    """

    _parameter_constraints = {
        "regressor": [BaseEstimator, None],
        "cutoff": [Interval(Real, 0, None, closed="neither"), None],
        "fs": [Interval(Real, 0, None, closed="neither")],
        "n_taps": [Interval(Integral, 1, None, closed="left")],
        "n_lead": [Interval(Integral, 0, None, closed="left")],
        "alpha": [Interval(Real, 0, None, closed="left"), "array-like"],
        "cv": [Interval(Integral, 2, None, closed="left"), "array-like", BaseCrossValidator, BaseShuffleSplit, None],
        "clearances": ["array-like", None],
        "n_integrations": [Interval(Integral, 0, None, closed="left")],
        "hidden_units": [Interval(Integral, 1, None, closed="left"), None],
        "in_band": ["boolean"],
        "window_stride": [Interval(Integral, 1, None, closed="left")],
        "n_networks": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Integral, None],
        "random_state": ["random_state"],
    }

    def __init__(self, regressor=None, *, cutoff=None, fs=1.0, n_taps=200, n_lead=0, alpha=1e-4, cv=None,
                 clearances=None, n_integrations=1, hidden_units=None, in_band=False, window_stride=2, n_networks=1,
                 n_jobs=None, random_state=None):
        self.regressor = regressor
        self.cutoff = cutoff
        self.fs = fs
        self.n_taps = n_taps
        self.n_lead = n_lead
        self.alpha = alpha
        self.cv = cv
        self.clearances = clearances
        self.n_integrations = n_integrations
        self.hidden_units = hidden_units
        self.in_band = in_band
        self.window_stride = window_stride
        self.n_networks = n_networks
        self.n_jobs = n_jobs
        self.random_state = random_state

    @validates_parameters
    def fit(self, X, y, **fit_params):
        """Fit ``regressor``, then the gate and the FIR filters on its error
        above ``cutoff``.

        Parameters
        ----------
        X : signals, as the regressor takes them
        y : signals with n_outputs channels, same layout and lengths
        **fit_params : dict
            Passed on to the regressor's ``fit`` (validation signals).

        Returns
        -------
        self
        """
        check_cutoff(self, y)
        if self.n_lead >= self.n_taps:
            raise ValueError(f"n_lead={self.n_lead} must be below n_taps={self.n_taps}: the filters reach from "
                             "n_lead samples ahead to n_taps - n_lead - 1 behind. Lower n_lead or raise n_taps.")
        if self.in_band and self.hidden_units is None:
            raise ValueError("in_band=True needs a network: pass hidden_units (e.g. 128), or in_band=False for "
                             "the FIR filters above the band.")
        if self.clearances is not None:
            clearances = np.asarray(self.clearances, dtype=float)
            if self.hidden_units is not None:
                raise ValueError("clearances: the hinges are inputs of the FIR filters; the network reads the "
                                 "prediction's window itself. Pass clearances=None with hidden_units.")
            if clearances.ndim != 1 or clearances.size == 0 or not np.all(np.isfinite(clearances)) \
                    or np.any(clearances < 0):
                raise ValueError(f"clearances={self.clearances!r}: pass a tuple of non-negative numbers (in units "
                                 "of each motion's largest training rms), e.g. (0.5, 1.0, 1.5), or None.")
        alphas = np.atleast_1d(np.asarray(self.alpha, dtype=float))
        if alphas.ndim != 1 or alphas.size == 0 or not np.all(np.isfinite(alphas)) or np.any(alphas < 0):
            raise ValueError(f"alpha={self.alpha!r}: pass a non-negative number, or several (a 1-D array-like) to "
                             "choose among by held-out signals (cv).")
        if alphas.size > 1 and self.hidden_units is not None:
            raise ValueError(f"alpha={self.alpha!r}: several penalties are chosen among for the FIR filters only; "
                             "pass one alpha with hidden_units.")
        X_list, y_list, _ = validate_signals(self, X, y, reset=True)
        splits = self._splits(len(X_list)) if alphas.size > 1 else []
        self.regressor_ = clone(self.regressor) if self.regressor is not None else BLAEstimator()
        self.regressor_.fit(X, y, **fit_params)
        self.n_outputs_ = y_list[0].shape[1]
        self._y_was_1d = signal_layout(y).kind == "1d"

        signals = [self._signal(U) for U in X_list]
        residual = [above_cutoff(Y - s.prediction, self.cutoff, self.fs) for s, Y in zip(signals, y_list)]
        self.above_band_rms_, self.state_scale_, self.gate_coef_ = fit_state_gate(signals, residual, self.cutoff,
                                                                                  self.fs)
        before_power = np.maximum(self.above_band_rms_ ** 2, np.finfo(float).tiny)
        if self.clearances is not None:
            motions = [self._motions(s) for s in signals]
            self.motion_scale_ = np.max([np.sqrt(np.mean(m**2, axis=0)) for m in motions], axis=0)
            self.motion_scale_[self.motion_scale_ == 0] = 1.0
            # the hinges in the gated input's units: computed once here in units of 1, then scaled
            self.hinge_scale_ = 1.0
            gated = [self._gated(s) for s in signals]
            kinks = [self._gated_hinges(s) for s in signals]
            gated_rms, hinge_rms = (np.sqrt(np.mean(np.vstack(w) ** 2)) for w in (gated, kinks))
            if gated_rms > 0 and hinge_rms > 0:
                self.hinge_scale_ = gated_rms / hinge_rms
            inputs = [self._map_input(s, g, self.hinge_scale_ * h) for s, g, h in zip(signals, gated, kinks)]
        else:
            inputs = [self._map_input(s) for s in signals]
        self.alpha_ = float(alphas[0])
        if self.hidden_units is None:
            ridge = FirRidge(inputs, residual, [s.periodic for s in signals], self.n_taps,
                             [train for train, _ in splits])
            if splits:
                self.cv_nrmse_ = np.array([
                    np.mean([self._held_out_nrmse(ridge.solve(alpha, k), [signals[i] for i in test],
                                                  [inputs[i] for i in test], [y_list[i] for i in test])
                             for k, (_, test) in enumerate(splits)])
                    for alpha in alphas])
                self.alpha_ = float(alphas[np.argmin(self.cv_nrmse_)])
            self.fir_ = ridge.solve(self.alpha_)
            self.n_map_params_ = self.gate_coef_.size + self.fir_.size
        else:
            # each signal relative to its own output power, as the NRMSE scores it (the outputs in units of the
            # error above the cutoff, with in_band too)
            weights = [1.0 / np.mean(np.mean(Y**2, axis=0) / before_power) for Y in y_list]
            if self.in_band:
                residual = [Y - s.prediction for s, Y in zip(signals, y_list)]
                before_power = np.maximum(np.mean(np.vstack(residual) ** 2, axis=0), np.finfo(float).tiny)
            self.networks_, self.network_input_scale_, self.network_output_scale_ = fit_networks(
                inputs, residual, weights, [held_out_rows(len(s.prediction), s.period) for s in signals],
                self.hidden_units, self.alpha_, self.n_networks, self.random_state, self.n_jobs)
            self.n_map_params_ = self.gate_coef_.size + sum(
                w.size for network in self.networks_ for w in network.coefs_ + network.intercepts_)
        self.n_params_ = state_space_n_params(self.regressor_) + self.n_map_params_
        after = [r - self._apply_map(i, s.periodic) for s, i, r in zip(signals, inputs, residual)]
        self.explained_fraction_ = 1.0 - np.mean(np.vstack(after) ** 2, axis=0) / before_power
        return self

    def _splits(self, n_signals):
        """``(train, test)`` signal indices of each split of ``cv``."""
        if self.cv is None:
            if n_signals < 2:
                raise ValueError(f"alpha={self.alpha!r}: choosing among several penalties holds training signals "
                                 "out, and there is one. Pass several signals, or one alpha.")
            cv = LeaveOneOut()
        else:
            cv = check_cv(self.cv)
        splits = [(np.asarray(train), np.asarray(test)) for train, test in cv.split(np.arange(n_signals))]
        if not splits or any(train.size == 0 or test.size == 0 or min(train.min(), test.min()) < 0
                             or max(train.max(), test.max()) >= n_signals for train, test in splits):
            raise ValueError(f"cv={self.cv!r}: every split must train on some of the {n_signals} signals and hold "
                             f"out others, by their indices 0 to {n_signals - 1}.")
        return splits

    def _held_out_nrmse(self, fir, signals, inputs, y_list):
        """The NRMSE of the regressor's and ``fir``'s simulation of held-out
        signals, averaged over them and their outputs."""
        return np.mean([np.sqrt(np.mean((Y - s.prediction - apply_fir(i, fir, s.periodic)) ** 2, axis=0)
                                / np.mean(Y**2, axis=0))
                        for s, i, Y in zip(signals, inputs, y_list)])

    def _signal(self, U):
        """One input signal as the model sees it (see ``_Signal``)."""
        return model_signal(self.regressor_, U, self.cutoff, self.fs)

    def _motions(self, signal):
        """The outputs' simulated motion in the band and each difference of
        two (``clearances``' variables)."""
        motion = integral_in_band(signal.prediction, self.cutoff / 16, self.cutoff, self.fs, self.n_integrations)
        return relative_motions(motion)

    def _gated_hinges(self, signal):
        """The hinges of the motions past each clearance, gated by the
        states as the input is (the motion says when a contact opens, the
        gate whether the joint knocks at that amplitude), kept above
        ``cutoff`` (their content in the band is the regressor's), in the
        filters' units."""
        kinks = hinges(self._motions(signal), self.motion_scale_, np.asarray(self.clearances, dtype=float))
        return self.hinge_scale_ * above_cutoff(self._gate(signal)[:, None] * kinks, self.cutoff, self.fs)

    def _gate(self, signal):
        """The gate along one signal, from its states."""
        return gate(signal.states / self.state_scale_, self.gate_coef_)

    def _gated(self, signal):
        """The input above ``cutoff``, gated by the states (and kept above it)."""
        return gated_input(signal, self.state_scale_, self.gate_coef_, self.cutoff, self.fs)

    def _ahead(self, w, signal):
        """``w`` read ``n_lead`` samples ahead: circularly on a periodic
        signal, with nothing after the end of another."""
        if self.n_lead == 0:
            return w
        if signal.periodic:
            return np.roll(w, -self.n_lead, axis=0)
        return np.vstack([w[self.n_lead :], np.zeros((min(self.n_lead, w.shape[0]), w.shape[1]))])

    def _map_input(self, signal, gated=None, kinks=None):
        """What the map above ``cutoff`` reads along one signal: for the FIR
        filters the gated input, and the hinges with ``clearances``; for the
        network, its windows of the prediction below ``cutoff`` beside the
        gated input. ``n_lead`` samples ahead. ``gated`` and ``kinks``: the
        signal's ``_gated`` and ``_gated_hinges`` when already computed."""
        gated = self._ahead(self._gated(signal) if gated is None else gated, signal)
        if self.hidden_units is None:
            if self.clearances is None:
                return gated
            kinks = self._gated_hinges(signal) if kinks is None else kinks
            return np.hstack([gated, self._ahead(kinks, signal)])
        below = signal.prediction - above_cutoff(signal.prediction, self.cutoff, self.fs)
        channels = [below, gated] + ([signal.input_below] if self.in_band else [])
        return windows(np.hstack(channels), self.n_taps, self.window_stride, signal.periodic)

    def _apply_map(self, map_input, periodic):
        """The modelled output above ``cutoff`` from ``_map_input``'s value."""
        if self.hidden_units is None:
            return apply_fir(map_input, self.fir_, periodic)
        return apply_networks(self.networks_, self.network_input_scale_, self.network_output_scale_, map_input)

    def predict(self, X):
        """The regressor's simulation plus the gated response above
        ``cutoff``.

        Parameters
        ----------
        X : signals, as in the regressor's ``predict``

        Returns
        -------
        y_pred : signals in the layout of ``X``
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        out = []
        for U in X_list:
            signal = self._signal(U)
            out.append(signal.prediction + self._apply_map(self._map_input(signal), signal.periodic))
        return restore_layout(out, layout, squeeze_1d=self._y_was_1d)
