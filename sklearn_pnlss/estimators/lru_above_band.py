"""The response above the excited band, learned by a deep recurrent network.

:class:`~sklearn_pnlss.AboveBandRegressor` maps a structure's knocking onto
its outputs through fixed features (the force above the band switched on
by a gate, hinges of the simulated motion) and FIR filters, all fitted by
least squares. How hard the joint knocks, and which modes ring, depends on
the motion in ways no fixed feature holds. Here a deep network of linear
recurrent units (LRU, Orvieto et al., ICML 2023) learns that map instead:
it reads the force, the force's content above the band and the model's own
simulation, and gives the part of the outputs above the band. Its
recursions are stable by construction and compiled (exact periodic steady
state for a periodic signal); it is fitted by Adam with exact gradients
(``_lru``: the adjoint recursion, no autodiff library). The model stays a
simulator of a new force: nothing measured at the output is read.
"""
from functools import partial
from numbers import Integral, Real

import numpy as np
from scipy import fft as sfft
from sklearn.base import BaseEstimator, clone
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from ..utils.parameters import Interval, Options, validates_parameters
from ..utils.validation import restore_layout, signal_layout, validate_signals
from ._base import DynamicRegressorMixin
from ._gated import above_cutoff, channel_rms
from ._lru import fit_networks
from .above_band import (check_cutoff, fit_state_gate, gated_input, model_signal, simulated,
                         state_space_n_params)
from .bla import BLAEstimator

__all__ = ["LRUAboveBandRegressor"]


class LRUAboveBandRegressor(DynamicRegressorMixin, BaseEstimator):
    """A state-space model plus a deep recurrent network of its response
    above the excited band.

    ``regressor`` is fitted as usual; a network of ``n_layers`` residual
    layers of linear recurrent units (each ``n_modes`` stable complex
    first-order recursions, a GELU, a linear mixing of ``width`` channels)
    then reads the input, the input's content above ``cutoff`` and the
    regressor's simulation, and is fitted by Adam to the regressor's
    simulation error above ``cutoff``. Its output is kept above ``cutoff``
    too, so the regressor's response in the band is left as it is. For
    structures whose joints knock: the impacts ring modes above the band at
    an amplitude and in a pattern that the motion sets, which a learned
    dynamic map holds better than fixed features through filters
    (:class:`AboveBandRegressor`).

    A periodic signal (length a multiple of the regressor's ``period``) is
    simulated in periodic steady state, exactly: the network's recursions
    are solved circularly over one period. Any other signal starts from
    rest. In training, a periodic signal is its periods' mean (the
    measurement's noise and what does not repeat average out), taken whole
    at every iteration; a signal from rest gives a random segment of
    ``segment_length`` samples an iteration, simulated from rest, its first
    ``burn_in`` samples not scored unless the segment starts the record.

    Parameters
    ----------
    regressor : estimator or None, default=None
        One of the library's regressors, a Pipeline ending in one, or an
        :class:`AveragedRegressor` of them (the gate then reads every
        member's states); None fits ``BLAEstimator()``. Cloned at fit; wrap
        a fitted model in :class:`sklearn.frozen.FrozenEstimator` to keep it
        as it is.
    cutoff : float or None, default=None
        The highest frequency the input excites, in the units of ``fs``:
        the content above it is modelled. Required.
    fs : float, default=1.0
        Sampling frequency.
    width : int, default=32
        Channels between the layers.
    n_layers : int, default=3
        Residual layers.
    n_modes : int, default=64
        Complex recursions per layer; their radii start uniform between 0.9
        and 0.9995 (time constants of 10 to 2,000 samples), their angles
        between 0 and 0.6 pi a sample (0.3 ``fs``).
    max_iter : int, default=300
        Adam iterations, on a one-cycle schedule (the step rises to
        ``learning_rate`` over the first tenth, then falls on a cosine).
    learning_rate : float, default=3e-3
        Adam's largest step.
    segment_length : int, default=16384
        Samples of each signal from rest an iteration takes.
    burn_in : int, default=4096
        Samples at a segment's start left out of its error (the network's
        recursions settle from rest; at most half the segment).
    gate : bool, default=True
        Whether the input's content above ``cutoff`` reaches the network
        switched on by a gate of the regressor's states (as
        :class:`AboveBandRegressor`'s: ``max(q(x), 0)``, ``q`` quadratic in
        the scaled states, fitted by least squares to where the regressor's
        error above ``cutoff`` lies in time). Where the joint does not
        knock, the force's content above the band then does not reach the
        network, which would otherwise put it on the outputs. False: the
        input's content above ``cutoff`` as it is.
    loss : {"nrmse", "squared"}, default="nrmse"
        What the network minimises over the training signals. "nrmse": the
        mean over the signals and outputs of the NRMSE of the whole
        simulation, as the field scores a model: the regressor's error in
        the band, which the network leaves alone, and its error above
        ``cutoff`` after the network (their powers add). Each output's
        error then weighs by the inverse of its NRMSE: a gain on the outputs
        and signals simulated best counts as much as the same relative gain
        on the worst. "squared": the mean of the NRMSE squared above
        ``cutoff``, where the worst-simulated outputs take the network.
    n_networks : int, default=1
        So many networks, from different initial weights and segments, are
        fitted and their outputs averaged: their errors partly cancel, for
        as many times the weights and the work.
    n_jobs : int or None, default=None
        With ``n_networks`` above 1: how many networks are fitted at a time,
        each in its own process with its share of the cores (joblib's
        convention: None one, -1 as many as there are cores). One network's
        products are too narrow to keep two cores busy: on the F-16 an
        iteration of one takes 0.40 s on two cores, of two side by side
        0.52 s.
    random_state : int, RandomState instance or None, default=None
        The networks' initial weights and the segments drawn (the k-th
        network's two seeds are the generator's draws ``2 k`` and ``2 k +
        1``). An int makes the fit reproducible, whatever ``n_jobs``.

    Attributes
    ----------
    regressor_ : estimator
        The fitted state-space model.
    networks_ : list of LRUNetwork
        The fitted networks (each one's ``params``), in units of their
        scaled inputs and outputs.
    input_scale_ : ndarray of shape (2 * n_inputs + n_outputs,)
        The training rms of the input, of its content above ``cutoff``
        (gated with ``gate``) and of the regressor's simulation: the
        network reads each divided by it.
    state_scale_ : ndarray of shape (n_states,)
        The rms of each state on the training signals (the gate's units).
        Only with ``gate``.
    gate_coef_ : ndarray of shape (1 + n_states * (n_states + 1) // 2,)
        The gate's coefficients (as :class:`AboveBandRegressor`'s). Only
        with ``gate``.
    output_scale_ : ndarray of shape (n_outputs,)
        The rms of the regressor's training error above ``cutoff``: the
        network's output is in its units.
    loss_curve_ : ndarray of shape (max_iter,)
        The training loss (``loss``) at each iteration, before the step
        (the networks' mean).
    n_iter_ : int
        The Adam iterations run (``max_iter``).
    explained_fraction_ : ndarray of shape (n_outputs,)
        The share of the regressor's training error power above ``cutoff``
        the networks' mean explains (periodic signals in steady state, the
        others from rest, whole).
    n_map_params_ : int
        The networks' weights (a complex one counts twice) and the gate's
        coefficients.
    n_params_ : int
        The state-space model's parameters and ``n_map_params_``.
    n_features_in_, n_outputs_ : int

    Notes
    -----
    On the F-16 ground vibration test (``benchmarks/f16_lru.py``), fitted
    on the estimation levels' multisines and sine sweeps on top of the
    benchmark's decoupled model of 18 states, two networks
    (``n_networks=2, n_jobs=2``) take the mean test NRMSE of the mean of
    two fits, each the better of two random starts (an
    :class:`AveragedRegressor`), from 0.170 - 0.180 to 0.128 - 0.137 over
    four draws, fitted in 143 to 157 s on 2 cores (``benchmarks/F16.md``
    has the figures). An iteration
    passes each periodic signal's period and one segment of each other
    signal forward and back: about ``24 n_layers n_modes width`` flops a
    sample in products with the weights, so the fit grows with
    ``max_iter`` and the number of signals, not with the records' lengths.
    On the F-16's 98304 samples an iteration takes 0.40 s on 2 cores, its
    products alone 0.29 s on one (``benchmarks/bench_lru_iteration.py``):
    the fit writes the intermediate signals to arrays it keeps over the
    iterations, whose pages are then zeroed once, not at every iteration.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sklearn_pnlss import BLAEstimator, LRUAboveBandRegressor
    >>> from sklearn_pnlss.metrics import nrmse_by_band
    >>> rng = np.random.default_rng(0)
    >>> def fast(u):  # the content of u above 0.1 cycles per sample
    ...     U = np.fft.rfft(u)
    ...     U[np.fft.rfftfreq(u.size) <= 0.1] = 0
    ...     return np.fft.irfft(U, u.size)
    >>> def record(n=4096):  # a slow force with some fast content; a rattle at large motion
    ...     u = lfilter([0.1], [1, -0.9], rng.standard_normal(n)) + 0.05 * rng.standard_normal(n)
    ...     y = lfilter([0.0, 0.1], [1, -0.9], u)
    ...     knock = np.maximum(y**2 - 2 * np.var(y), 0) * fast(u)
    ...     return u[:, None], (y + lfilter([0.0, 1.0], [1, 0.5], knock))[:, None]
    >>> (u, y), (u_2, y_2), (u_new, y_new) = record(), record(), record()
    >>> model = LRUAboveBandRegressor(BLAEstimator(2, fs=1.0), cutoff=0.1, width=8, n_layers=2, n_modes=16,
    ...                               max_iter=200, segment_length=2048, burn_in=128, random_state=0)
    >>> model = model.fit([u, u_2], [y, y_2])
    >>> def error_above(m):  # NRMSE of the new record above the cutoff
    ...     return float(nrmse_by_band(y_new, m.predict(u_new), fs=1.0, edges=(0.1, 0.51))[0, 0])
    >>> round(error_above(model.regressor_), 4), round(error_above(model), 4)
    (0.0121, 0.0043)
    """

    _parameter_constraints = {
        "regressor": [BaseEstimator, None],
        "cutoff": [Interval(Real, 0, None, closed="neither"), None],
        "fs": [Interval(Real, 0, None, closed="neither")],
        "width": [Interval(Integral, 1, None, closed="left")],
        "n_layers": [Interval(Integral, 1, None, closed="left")],
        "n_modes": [Interval(Integral, 1, None, closed="left")],
        "max_iter": [Interval(Integral, 1, None, closed="left")],
        "learning_rate": [Interval(Real, 0, None, closed="neither")],
        "segment_length": [Interval(Integral, 2, None, closed="left")],
        "burn_in": [Interval(Integral, 0, None, closed="left")],
        "gate": ["boolean"],
        "loss": [Options(str, {"nrmse", "squared"})],
        "n_networks": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Integral, None],
        "random_state": ["random_state"],
    }

    def __init__(self, regressor=None, *, cutoff=None, fs=1.0, width=32, n_layers=3, n_modes=64, max_iter=300,
                 learning_rate=3e-3, segment_length=16384, burn_in=4096, gate=True, loss="nrmse", n_networks=1,
                 n_jobs=None, random_state=None):
        self.regressor = regressor
        self.cutoff = cutoff
        self.fs = fs
        self.width = width
        self.n_layers = n_layers
        self.n_modes = n_modes
        self.max_iter = max_iter
        self.learning_rate = learning_rate
        self.segment_length = segment_length
        self.burn_in = burn_in
        self.gate = gate
        self.loss = loss
        self.n_networks = n_networks
        self.n_jobs = n_jobs
        self.random_state = random_state

    @validates_parameters
    def fit(self, X, y, **fit_params):
        """Fit ``regressor``, then the network on its error above ``cutoff``.

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
        X_list, y_list, _ = validate_signals(self, X, y, reset=True)
        rng = check_random_state(self.random_state)
        self.regressor_ = clone(self.regressor) if self.regressor is not None else BLAEstimator()
        self.regressor_.fit(X, y, **fit_params)
        self.n_outputs_ = y_list[0].shape[1]
        self._y_was_1d = signal_layout(y).kind == "1d"

        model_signals = [None] * len(X_list)
        if self.gate:
            model_signals = [model_signal(self.regressor_, U, self.cutoff, self.fs) for U in X_list]
            residual = [above_cutoff(Y - s.prediction, self.cutoff, self.fs) for s, Y in zip(model_signals, y_list)]
            _, self.state_scale_, self.gate_coef_ = fit_state_gate(model_signals, residual, self.cutoff, self.fs)
        views = [self._view(U, s) for U, s in zip(X_list, model_signals)]
        errors = [self._one_period(Y - p, period) for Y, (_, p, period) in zip(y_list, views)]
        targets = [above_cutoff(e, self.cutoff, self.fs) for e in errors]
        self.input_scale_ = channel_rms([v for v, _, _ in views])
        self.output_scale_ = channel_rms(targets)
        power = [np.maximum(np.mean(self._one_period(Y, period) ** 2, axis=0), np.finfo(float).tiny)
                 for Y, (_, _, period) in zip(y_list, views)]
        # what the network leaves alone: the error in the band, each signal's and output's NRMSE squared
        floors = [np.mean((e - t) ** 2, axis=0) / pw if self.loss == "nrmse" else None
                  for e, t, pw in zip(errors, targets, power)]
        signals = [(v / self.input_scale_, t / self.output_scale_, self.output_scale_**2 / pw, period is not None,
                    floor) for (v, _, period), t, pw, floor in zip(views, targets, power, floors)]
        # every network's seeds drawn here, in order: the same networks whatever n_jobs
        seeds = [(rng.randint(2**32), rng.randint(2**32)) for _ in range(self.n_networks)]
        settings = (self.input_scale_.size, self.n_outputs_, self.width, self.n_layers, self.n_modes)
        training = (self.max_iter, self.learning_rate, self.segment_length, self.burn_in)
        fitted = fit_networks(settings, signals, training, seeds, partial(_above_cutoff, self.cutoff, self.fs),
                              self.n_jobs)
        self.networks_ = [network for network, _ in fitted]
        self.loss_curve_ = np.mean([losses for _, losses in fitted], axis=0)
        self.n_iter_ = self.loss_curve_.size
        after = [t - self._network_output(v, period) for (v, _, period), t in zip(views, targets)]
        self.explained_fraction_ = 1.0 - (np.mean(np.vstack(after) ** 2, axis=0)
                                          / np.maximum(np.mean(np.vstack(targets) ** 2, axis=0), np.finfo(float).tiny))
        self.n_map_params_ = sum(n.n_params for n in self.networks_) + (self.gate_coef_.size if self.gate else 0)
        self.n_params_ = state_space_n_params(self.regressor_) + self.n_map_params_
        return self

    def _view(self, U, signal=None):
        """What the network reads along one signal (the input, its content
        above ``cutoff``, gated with ``gate``, and the regressor's
        simulation), over one period if the signal is periodic (its
        periods' mean); the simulation over the whole signal; and the
        period, or None. ``signal``: ``U`` as the regressor sees it
        (``model_signal``), when already computed (with ``gate``)."""
        if self.gate:
            signal = model_signal(self.regressor_, U, self.cutoff, self.fs) if signal is None else signal
            above, prediction, period = (gated_input(signal, self.state_scale_, self.gate_coef_, self.cutoff,
                                                     self.fs), signal.prediction, signal.period)
        else:
            _, period, prediction = simulated(self.regressor_, U)
            above = above_cutoff(U, self.cutoff, self.fs)
        return self._one_period(np.hstack([U, above, prediction]), period), prediction, period

    @staticmethod
    def _one_period(signal, period):
        """The mean of a periodic signal's periods, or the signal."""
        if period is None:
            return signal
        return signal.reshape(-1, period, signal.shape[1]).mean(axis=0)

    def _network_output(self, view, period):
        """The networks' mean output in its units of the regressor's error
        (one period in steady state, or from rest)."""
        periodic, scaled = period is not None, view / self.input_scale_
        out = np.mean([network.forward(scaled, periodic) for network in self.networks_], axis=0)
        return _above_cutoff(self.cutoff, self.fs, out, periodic) * self.output_scale_

    def predict(self, X):
        """The regressor's simulation plus the network's response above
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
            view, prediction, period = self._view(U)
            above = self._network_output(view, period)
            if period is not None:
                above = np.tile(above, (U.shape[0] // period, 1))
            out.append(prediction + above)
        return restore_layout(out, layout, squeeze_1d=self._y_was_1d)



def _above_cutoff(cutoff, fs, out, periodic):
    """The content of a network's output above ``cutoff``: circularly over
    a period, else over the signal padded with as many zeros (a symmetric
    filter, its own adjoint)."""
    n_fft = None if periodic else sfft.next_fast_len(2 * out.shape[0], real=True)
    return above_cutoff(out, cutoff, fs, n_fft)
