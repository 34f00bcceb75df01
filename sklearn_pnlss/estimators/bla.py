"""BLAEstimator: best linear approximation and a linear state-space model."""
import warnings
from numbers import Integral, Real

import numpy as np

from ..frequency.bla import periodic_bla, welch_bla
from ..statespace.linear import (frequency_response, is_stable, modal_parameters, peak_gain, simulate_linear,
                                simulate_linear_signal)
from ..statespace.scaled import linear_scaled_model
from ..statespace.subspace import fd_refine, fd_subspace, frf_weights
from ..utils.parameters import Interval, validates_parameters
from ..utils.threads import blas_threads_for
from ..utils.validation import check_period
from ._base import SignalRegressorBase

__all__ = ["BLAEstimator"]


# Above this mean ratio of squared misfit to the FRF variance, the misfit is
# taken for model error and the weighting is widened by its mean (see
# BLAEstimator._fit_parametric).
MISFIT_RATIO = 10.0
# Relative drop of the weighted misfit for which a later start of the linear
# fit replaces an earlier one (equal fits keep the first, the plain subspace).
TIE = 0.01


def _weighted_misfit(model, G, z, var):
    """Mean squared misfit of the model's FRF in the weights of the fit."""
    w = frf_weights(G, var)
    with np.errstate(all="ignore"):
        cost = np.mean(np.abs(frequency_response(*model, z) - G) ** 2 * (w**2)[:, None, None])
    return cost if np.isfinite(cost) else np.inf


def _record_error(model, in_scale, out_scale, scale, records):
    """Mean squared simulation error of a scaled FRF fit on ``records``
    (each output in units of its own rms), each record started from the
    state that fits it best (least squares over the record: the state a
    record without periods starts in is unknown)."""
    A, B, C, D = model
    B, C, D = B * in_scale[None, :], out_scale[:, None] * C, scale * D
    if not np.all(np.isfinite(A)) or np.max(np.abs(np.linalg.eigvals(A))) >= 1.0:
        return np.inf
    n = A.shape[0]
    total = 0.0
    for U, Y in records:
        forced = simulate_linear(A, B, C, D, U)[0]
        # the free responses from each unit state: the record's state columns
        free = np.stack([simulate_linear(A, B, C, np.zeros_like(D), np.zeros_like(U), x0)[0] for x0 in np.eye(n)],
                        axis=-1)
        weight = 1.0 / np.maximum(np.std(Y, axis=0), 1e-300)
        lhs = (free * weight[None, :, None]).reshape(-1, n)
        rhs = ((Y - forced) * weight).ravel()
        x0 = np.linalg.lstsq(lhs, rhs, rcond=None)[0]
        total += np.mean((rhs - lhs @ x0) ** 2)
    return total / len(records)


def _to_db_power(x):
    with np.errstate(divide="ignore"):
        return 10 * np.log10(x)


def _warn_operating_point(X_list, y_list):
    """Warn when a channel's mean exceeds its standard deviation: the
    signals vary around an operating point, which a model through the
    origin cannot hold together with the gain of the variations."""
    for name, signals in (("X", X_list), ("y", y_list)):
        stacked = np.concatenate(signals)
        mean, std = np.mean(stacked, axis=0), np.std(stacked, axis=0)
        if np.any(np.abs(mean) > std):
            k = int(np.argmax(np.abs(mean) - std))
            warnings.warn(
                f"{name} channel {k} has a mean of {mean[k]:.4g}, beyond its standard deviation "
                f"{std[k]:.4g}: the signals vary around an operating point, which a model through "
                "the origin cannot hold. Set offsets=True to model the deviations from it.",
                UserWarning, stacklevel=4,
            )
            return


class BLAEstimator(SignalRegressorBase):
    """Best linear approximation (BLA) and a linear state-space model of it.

    From periodic multisine data (``period`` set): the nonparametric BLA per
    excited line, with the noise variance (spread over periods), the total
    variance (spread over realisations) and the stochastic nonlinear
    distortion (their difference); the output levels at non-excited odd and
    even lines reveal odd and even nonlinearities. A discrete-time model
    ``x(t+1) = A x + B u, y = C x + D u`` of order ``n_states`` is then found
    by frequency-domain subspace identification weighted by the BLA
    variance, and refined by a weighted least-squares fit of the FRF.

    Each output and input is first put in units of its own FRF level, so
    that all count alike. When that fit misses the BLA by far more than its
    variance (mean squared weighted misfit above 10: one realisation of a
    nonlinear system, whose stochastic distortion is in the BLA but not in
    its variance; a structure with many lightly damped modes in a narrow
    band, such as the F-16 of :func:`~sklearn_pnlss.datasets.load_f16`), the
    misfit is model error: the variance is widened by its mean, and the fit
    is redone from several starts (the plain one; subspace fits on a
    frequency axis warped to spread the band over the unit circle, with
    ``2n``, ``n + 1`` and ``3n`` block rows), each refined with its poles
    kept within a decay of ``1/e`` per period and its gain outside the
    excited band at most the largest measured in it; the best fit is kept.
    A first fit within the variance goes the same way when its poles
    outlast a period or its gain outside the band is 3 dB above both the
    largest measured and its subspace start's (spare states, free to go
    where the data do not look).

    Without ``period`` the BLA comes from Welch's H1 estimator on the whole
    signals (random excitation).

    Parameters
    ----------
    n_states : int, default=3
        Model order.
    period : int or None, default=None
        Samples per period. With a period, training signals must hold whole
        steady-state periods (length a multiple of ``period``); in
        :meth:`predict` such signals are simulated in periodic steady state and
        any other signal from rest.
    fs : float or None, default=None
        Sampling frequency in Hz, used for reporting only (``frequencies_``,
        ``natural_frequencies_``); None means cycles per sample.
    lines : array-like of int or None, default=None
        Excited DFT bins of one period. When None, found from the input
        spectrum: the bins within -60 dB of the strongest, less those below a
        drop of 20 dB or more in the sorted bin powers that hold under 1 % of
        the input power (mains hum, leakage or noise of a measured force).
    refine : bool, default=True
        Refine the subspace model by weighted nonlinear least squares.
    feedthrough : bool, default=True
        Estimate the direct term D (else D = 0).
    n_block_rows : int or None, default=None
        Block rows of the subspace's observability matrix; ``2 n_states``
        (and, when that fit misses the BLA, also ``n_states + 1`` and
        ``3 n_states``) when None.
    nperseg : int or None, default=None
        Segment length of the Welch estimate (``period=None`` only).
    offsets : bool, default=False
        Model the deviations of the signals from their training means: the
        BLA is the linear map between deviations around an operating point
        (a pump's mean voltage and the water level it holds, a sensor's
        zero), and the model predicts ``output_offset_ + G (u -
        input_offset_)``; its rest is that operating point. The nonlinear
        estimators started from this model keep its offsets, and
        :class:`PNLSSRegressor` adds a constant term to each nonlinear
        equation (its even terms shift the means, which the offsets already
        hold). False, as the PNLSS toolbox: the model passes through the
        origin (zero-mean excitation such as multisines, where an even
        nonlinearity's DC output is the polynomial's to produce); a warning
        says when the training signals sit around an operating point
        instead (a channel's mean beyond its standard deviation).

    Attributes
    ----------
    A_, B_, C_, D_ : ndarray
        The linear model (of the deviations from the offsets).
    input_offset_, output_offset_ : ndarray of shape (n_inputs,), (n_outputs,)
        The operating point: the training means with ``offsets``, else zero.
    model_ : ScaledModel
        The same model as the nonlinear estimators' fitted model (a
        :class:`~sklearn_pnlss.ScaledModel` around a
        polynomial model without monomials, unit scales): it simulates
        (``model_.simulate(U, period)``) and exports itself
        (``model_.in_user_units()``).
    lines_ : ndarray of int
        Excited DFT bins the BLA is estimated at.
    frequencies_ : ndarray
        Their frequencies (Hz, or cycles/sample without ``fs``).
    frf_ : ndarray of shape (n_lines, n_outputs, n_inputs), complex
        Nonparametric BLA.
    frf_var_total_, frf_var_noise_, frf_var_nonlinear_ : ndarray
        Variances of ``frf_`` (the averaged estimate): total (noise plus
        stochastic nonlinear distortion), noise, and nonlinear distortion.
        NaN where the data cannot tell (one period: no noise estimate).
    frf_model_ : ndarray
        FRF of the fitted linear model at ``lines_``.
    output_level_, noise_level_ : ndarray of shape (n_bins, n_outputs)
        Output power and noise power at every bin of a period (periodic data).
    line_kind_ : ndarray of int of shape (n_bins,)
        0 DC, 1 excited, 2 non-excited odd, 3 non-excited even.
    distortion_levels_ : dict
        Mean output power in dB at excited lines and at the odd and even
        detection lines inside the excited band, and the noise level; NaN
        where no such line exists (e.g. full multisine).
    natural_frequencies_, damping_ratios_ : ndarray
        Modal parameters of the model's poles.
    n_params_ : int
        Number of model parameters, ``n^2 + n m + p n + p m``.
    n_realizations_, n_periods_ : int
    n_features_in_ : int
        Number of inputs.
    n_outputs_ : int

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sklearn_pnlss import BLAEstimator
    >>> from sklearn_pnlss.signals import multisine
    >>> X, lines = multisine(256, fs=1.0, f_band=(0.01, 0.4), n_periods=2,
    ...                      n_realizations=2, random_state=0)
    >>> y = np.stack([np.tile(lfilter([0.0, 0.5], [1, -0.6], np.tile(x[:256, 0], 3))[-256:], 2)
    ...               for x in X])[..., None]
    >>> model = BLAEstimator(n_states=1, period=256).fit(X, y)
    >>> round(float(np.linalg.eigvals(model.A_)[0].real), 6)
    0.6
    """

    _parameter_constraints = {
        "n_states": [Interval(Integral, 1, None, closed="left")],
        "period": [Interval(Integral, 2, None, closed="left"), None],
        "fs": [Interval(Real, 0, None, closed="neither"), None],
        "lines": ["array-like", None],
        "refine": ["boolean"],
        "feedthrough": ["boolean"],
        "n_block_rows": [Interval(Integral, 2, None, closed="left"), None],
        "nperseg": [Interval(Integral, 4, None, closed="left"), None],
        "offsets": ["boolean"],
    }

    def __init__(
        self,
        n_states=3,
        *,
        period=None,
        fs=None,
        lines=None,
        refine=True,
        feedthrough=True,
        n_block_rows=None,
        nperseg=None,
        offsets=False,
    ):
        self.n_states = n_states
        self.period = period
        self.fs = fs
        self.lines = lines
        self.refine = refine
        self.feedthrough = feedthrough
        self.n_block_rows = n_block_rows
        self.nperseg = nperseg
        self.offsets = offsets

    @validates_parameters
    def fit(self, X, y):
        """Estimate the BLA and its linear state-space model.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), list of
            2-D signals, or one 1-D/2-D signal
            Input signals. With ``period``: steady-state periodic, each a whole
            number of periods; one signal per realisation.
        y : signals of shape (..., n_outputs)
            Measured outputs, same layout and lengths.

        Returns
        -------
        self
        """
        X_list, y_list = self._validate_fit_data(X, y)
        period = check_period(self.period)
        if self.offsets:
            self.input_offset_ = np.mean(np.concatenate(X_list), axis=0)
            self.output_offset_ = np.mean(np.concatenate(y_list), axis=0)
        else:
            self.input_offset_ = np.zeros(X_list[0].shape[1])
            self.output_offset_ = np.zeros(y_list[0].shape[1])
            _warn_operating_point(X_list, y_list)
        records = None
        if period is None:
            self._fit_welch(X_list, y_list)
            records = [(U - self.input_offset_, Y - self.output_offset_) for U, Y in zip(X_list, y_list)]
        else:
            self._fit_periodic(X_list, y_list, period)
        # the subspace step's QR (lines by block rows times channels) is the
        # largest product; on one BLAS thread below a few hundred Mflop
        n_lines, p, m = self.frf_.shape
        with blas_threads_for(2 * (2 * n_lines * m) * (3 * self.n_states * (m + p)) ** 2):
            self._fit_parametric(records)
        return self

    def _fit_periodic(self, X_list, y_list, period):
        U_periods, Y_periods = [], []
        for i, (U, Y) in enumerate(zip(X_list, y_list)):
            if U.shape[0] % period:
                raise ValueError(
                    f"Signal {i} has {U.shape[0]} samples, not a multiple of "
                    f"period={period}: BLAEstimator.fit needs whole steady-state "
                    "periods. Trim the signal, or set period=None for a Welch "
                    "estimate from non-periodic data."
                )
            P = U.shape[0] // period
            U_periods.append(U.reshape(P, period, U.shape[1]))
            Y_periods.append(Y.reshape(P, period, Y.shape[1]))
        lines = None if self.lines is None else np.asarray(self.lines, dtype=int)
        if lines is not None and (lines.min() < 1 or lines.max() > period // 2):
            raise ValueError(
                f"lines must be DFT bins between 1 and period // 2 = {period // 2}; "
                f"got values from {lines.min()} to {lines.max()}."
            )
        bla = periodic_bla(U_periods, Y_periods, lines)
        self._n_per_period = period
        self.lines_ = bla.lines
        self.frf_ = bla.frf
        self.frf_var_total_ = bla.var_total
        self.frf_var_noise_ = bla.var_noise
        self.frf_var_nonlinear_ = bla.var_nonlinear
        self.output_level_ = bla.output_level
        self.noise_level_ = bla.noise_level
        self.line_kind_ = bla.line_kind
        self.n_realizations_ = bla.n_realizations
        self.n_periods_ = bla.n_periods
        self.distortion_levels_ = self._distortion_levels()

    def _distortion_levels(self):
        band = np.zeros_like(self.line_kind_, dtype=bool)
        band[self.lines_.min() : self.lines_.max() + 1] = True
        levels = {}
        for name, kind in (("excited", 1), ("odd", 2), ("even", 3)):
            sel = band & (self.line_kind_ == kind)
            levels[name] = float(_to_db_power(np.mean(self.output_level_[sel]))) if sel.any() else np.nan
        noise = self.noise_level_[band]
        levels["noise"] = float(_to_db_power(np.mean(noise))) if np.all(np.isfinite(noise)) else np.nan
        return levels

    def _fit_welch(self, X_list, y_list):
        n_min = min(U.shape[0] for U in X_list)
        nperseg = self.nperseg or int(np.clip(2 ** int(np.log2(max(n_min // 4, 1))), 16, 4096))
        nperseg = min(nperseg, n_min)
        lines, frf, var = welch_bla(X_list, y_list, nperseg)
        self._n_per_period = nperseg
        self.lines_ = lines
        self.frf_ = frf
        self.frf_var_total_ = var
        self.frf_var_noise_ = np.full(var.shape, np.nan)
        self.frf_var_nonlinear_ = np.full(var.shape, np.nan)
        self.n_realizations_ = len(X_list)
        self.n_periods_ = 0
        self.distortion_levels_ = {k: np.nan for k in ("excited", "odd", "even", "noise")}

    def _fit_parametric(self, records=None):
        """The state-space model of the FRF; ``records``: the training
        records (less their offsets) of a Welch estimate, by which the
        candidate fits are judged."""
        z = np.exp(2j * np.pi * self.lines_ / self._n_per_period)
        var = self.frf_var_total_
        if not np.all(np.isfinite(var)):
            var = None
        n_lines, p, m = self.frf_.shape
        n = self.n_states
        if n_lines * m < 2 * n + 1:
            raise ValueError(
                f"{n_lines} excited line(s) in X cannot determine a model with "
                f"n_states={n}; use longer signals or a lower n_states."
            )
        level = np.sqrt(np.mean(np.abs(self.frf_) ** 2))
        if not (np.isfinite(level) and level > 0):
            raise ValueError(
                "y does not respond to X at the excited lines (the BLA is zero): a zero or "
                "constant output holds no dynamics to identify; check that y is the "
                "output measured with input X."
            )
        # Each output and input in units of its own FRF level, so that every
        # channel counts alike in relative terms (the simulation error per
        # output), however different their sizes; undone on the model below.
        out_scale = np.sqrt(np.mean(np.abs(self.frf_) ** 2, axis=(0, 2)))
        out_scale = np.where(out_scale > 0, out_scale, 1.0)
        in_scale = np.sqrt(np.mean(np.abs(self.frf_ / out_scale[:, None]) ** 2, axis=(0, 1)))
        in_scale = np.where(in_scale > 0, in_scale, 1.0)
        scale = out_scale[:, None] * in_scale[None, :]
        G = self.frf_ / scale
        var = None if var is None else var / scale**2

        # The plain fit: subspace on z itself, refined with free steps.
        rows = [self.n_block_rows] if self.n_block_rows else [max(n + 1, 2 * n), n + 1, 3 * n]
        q_max = max(n + 1, (n_lines * m - n) // m)
        subspace = fd_subspace(G, z, n, var=var, q=min(rows[0], q_max), estimate_d=self.feedthrough, warp=None)
        plain = subspace
        if self.refine:
            plain = fd_refine(*plain, G, z, var=var, estimate_d=self.feedthrough, warp=None, stay_stable=False)
        if (records is None and var is not None and _weighted_misfit(plain, G, z, var) <= MISFIT_RATIO
                and self._within_limits(plain, subspace, G)):
            # A fit at the level of the FRF variance is kept: other starts
            # could only fit the noise better. But with spare states the
            # free steps reach that level by chance, and where they do not
            # look: on the F-16's four levels at 18 states a relative change
            # of 1e-14 in the input moved the free fit's misfit from 4.9 to
            # 31 times the variance, and the fit under 10 had made a
            # resonance at 21.7 Hz, 2.7 times the largest gain measured or
            # started from; the decoupled model fitted from it tested 0.246
            # NRMSE, from the constrained fits 0.189.
            A, B, C, D = plain
        else:
            if var is not None:
                # A misfit far above the variance (one realisation of a
                # nonlinear system: the stochastic distortion is in G but not
                # in the variance; a structure with more modes than states; a
                # fit lost on a narrow band) is model error, about flat over
                # the band: weighting by the noise alone would fit the quiet
                # lines and give up the resonances that carry the output.
                # Widen the variance by the mean misfit.
                var = var + np.mean(np.abs(frequency_response(*plain, z) - G) ** 2)
            # Then the plain fit refined again under constraints, and fits
            # from subspace starts on the warped axis (see
            # statespace.subspace) with 2n, n + 1 and 3n block rows.
            starts = [("auto", min(q, q_max)) for q in rows]
            refined = self._refine(plain, G, z, var, None)
            if records is None:
                A, B, C, D = self._fit_frf(G, z, var, starts, start=refined)
            else:
                # Records without periods: Welch's variance is read from the
                # coherence over segments; it holds the nonlinear distortion
                # and the leakage, at a fine resolution so widely that FRF
                # fits far apart in the time domain pass as equal (WH2009 at
                # 4096 lines a segment: the plain fit, 5.7 times the
                # variance, tested 71.8 mV where other starts give 57.4 mV).
                # The candidates are judged as the BLA is used: by their
                # simulation error on the records.
                candidates = [plain, refined] + [self._start_fit(G, z, var, *start) for start in dict.fromkeys(starts)]
                A, B, C, D = min(candidates, key=lambda m: _record_error(m, in_scale, out_scale, scale, records))
        B, C, D = B * in_scale[None, :], out_scale[:, None] * C, scale * D

        self.A_, self.B_, self.C_, self.D_ = A, B, C, D
        self.model_ = linear_scaled_model(A, B, C, D, self.input_offset_, self.output_offset_)
        self.frf_model_ = frequency_response(A, B, C, D, z)
        fs = 1.0 if self.fs is None else float(self.fs)
        self.frequencies_ = self.lines_ * fs / self._n_per_period
        self.natural_frequencies_, self.damping_ratios_ = modal_parameters(A, fs)
        self.n_params_ = n * n + n * m + p * n + p * m

    def _refine(self, model, G, z, var, warp):
        """Refine a subspace start: first within the unit circle only, then
        with its poles kept within a period's decay (those beyond are moved
        onto that radius); the gain outside the excited band capped
        throughout."""
        if not self.refine:
            return model
        kw = dict(var=var, estimate_d=self.feedthrough, warp=warp, bound=np.max(np.abs(G), axis=0),
                  bound_points=self._outside_points())
        model = fd_refine(*model, G, z, **kw)
        return fd_refine(*model, G, z, stability_margin=self._decay_margin(), **kw)

    def _outside_points(self):
        """Up to 2048 points of the unit circle at the lines outside the
        excited band, where the refinement caps the model's gain."""
        N = self._n_per_period
        outside = np.ones(N // 2 + 1, dtype=bool)  # a mask, not np.setdiff1d: its sort took 3 ms of 50 a BLA
        outside[self.lines_[(self.lines_ >= 0) & (self.lines_ <= N // 2)]] = False
        outside = np.flatnonzero(outside)
        outside = outside[np.linspace(0, outside.size - 1, min(outside.size, 2048)).astype(int)]
        return np.exp(2j * np.pi * outside / N)

    def _decay_margin(self):
        """A pole whose response outlasts a period contradicts the steady
        state the BLA is measured in (the transient of the first period
        would not have died out): ``|pole|^period <= 1/e``."""
        return -np.expm1(-1.0 / self._n_per_period)

    def _within_limits(self, model, start, G):
        """Whether the free refinement ``model`` of the subspace fit
        ``start`` keeps within what :meth:`_refine` holds the other fits
        to: its poles within a period's decay, and no gain outside the band
        more than 3 dB above both the largest measured at the lines (``G``)
        and the start's own there (a resonance the data put just outside
        the band is kept; one the free steps made up is not)."""
        if not self.refine:
            return True
        if not is_stable(model[0], margin=self._decay_margin()):
            return False
        points = self._outside_points()
        allowed = np.maximum(np.max(np.abs(G), axis=0), peak_gain(*start, points))
        return bool(np.all(peak_gain(*model, points) <= np.sqrt(2.0) * allowed))

    def _start_fit(self, G, z, var, warp, q):
        """The subspace fit with ``q`` block rows on the ``warp`` axis, refined."""
        model = fd_subspace(G, z, self.n_states, var=var, q=q, estimate_d=self.feedthrough, warp=warp)
        return self._refine(model, G, z, var, warp)

    def _fit_frf(self, G, z, var, starts, start):
        """``start``, or a refined subspace fit from one of ``starts``
        ((warp, block rows) pairs) that lowers the weighted misfit by more
        than ``TIE`` of the best so far."""
        best, best_cost = start, _weighted_misfit(start, G, z, var)
        for warp, q in dict.fromkeys(starts):
            model = self._start_fit(G, z, var, warp, q)
            cost = _weighted_misfit(model, G, z, var)
            if cost < (1 - TIE) * best_cost:
                best, best_cost = model, cost
        return best

    def _predict_signal(self, U, periodic):
        period = self.period if periodic else None
        y = simulate_linear_signal(self.A_, self.B_, self.C_, self.D_, U - self.input_offset_, periodic_with=period)
        return y + self.output_offset_

    def _summary_structure(self):
        source = (
            f"{self.n_realizations_} realisation(s) x {self.n_periods_} period(s)" if self.n_periods_
            else f"Welch, {self.n_realizations_} signal(s)"
        )
        return {"excited_lines": int(self.lines_.size), "data": source}

    def _summary_fit(self):
        # The levels tell what a linear model leaves out: nonlinear
        # distortion at the detection lines, noise below it.
        levels = {k: v for k, v in self.distortion_levels_.items() if np.isfinite(v)}
        err = self.frf_model_ - self.frf_
        with np.errstate(divide="ignore"):
            fit = {"frf_model_error_db": float(20 * np.log10(np.sqrt(np.mean(np.abs(err) ** 2))))}
        if levels:
            fit["output_levels_db"] = levels
        return fit

    def plot(self, ax=None):
        """FRF of the BLA with the noise and nonlinear distortion levels.

        See :func:`sklearn_pnlss.plotting.plot_bla`.
        """
        from ..plotting import plot_bla

        return plot_bla(self, ax=ax)
