"""What the nonlinear state-space regressors share: ``fit`` (validation of
the signals, the start model each estimator builds, then the fitting engine
of :mod:`sklearn_pnlss.statespace.fitting`), and simulation for predict.

Where a fit happens: :meth:`StateSpaceRegressorBase.fit`, here.
"""
import warnings
from dataclasses import replace
from numbers import Integral, Real

import numpy as np
from sklearn.utils.validation import check_is_fitted

from ..statespace.fitting import TIME_DOMAIN_WEIGHTINGS, FitSettings, relative_weights, simulation_objectives
from ..statespace.model_base import DivergenceError
from ..statespace.new_inputs import random_phase_inputs, training_periods
from ..statespace.scaled import normalised_linear_start
from ..utils.handover import detach_stage
from ..utils.parameters import Interval, Options, validates_parameters
from ..utils.validation import as_signal_list, check_period, validate_signals
from ._base import SignalRegressorBase

__all__ = ["StateSpaceRegressorBase"]

# Constraints of the fit parameters every subclass has (see the docstring).
FIT_PARAMETER_CONSTRAINTS = {
    "range_margin": [Interval(Real, 0, None, closed="left")],
    "stable_at_rest": ["boolean"],
    "period": [Interval(Integral, 2, None, closed="left"), None],
    "average_periods": ["boolean"],
    "weighting": [None, Options(str, {"relative", "band", "noise"})],
    "band": [tuple, list, None],
    "max_iter": [Interval(Integral, 0, None, closed="left")],
    "tol": [Interval(Real, 0, None, closed="left")],
    "n_transient": [Interval(Integral, 0, None, closed="left"), Options(str, {"auto"})],
    "verbose": ["verbose"],
    "random_state": ["random_state"],
}


class StateSpaceRegressorBase(SignalRegressorBase):
    """Base of the regressors fitted by Levenberg-Marquardt on the
    simulation error (see :mod:`sklearn_pnlss.statespace.fitting`).

    This base owns ``fit``; a subclass gives the one thing that differs:
    its start, ``_fit_start`` (a
    :class:`~sklearn_pnlss.statespace.scaled.ScaledModel`), how the engine
    runs from it, ``_fit_from_start``, and its exported attributes,
    ``_export``. The fitted model is ``model_``. Subclasses need the
    parameters ``period``, ``average_periods``, ``weighting``, ``band``,
    ``max_iter``, ``tol``, ``n_transient``, ``extrapolation``,
    ``range_margin``, ``stable_at_rest`` and ``verbose``.
    """

    @validates_parameters
    def fit(self, X, y, *, X_val=None, y_val=None, time_weight=None, X_check=None, y_check=None):
        """Fit the start model, then the full model by Levenberg-Marquardt.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), list of
            2-D signals, or one 1-D/2-D signal
        y : signals with n_outputs channels, same layout and lengths
        X_val, y_val : signals or None, default=None
            Validation signals: the iterate with the lowest rms simulation
            error on them is kept (the toolbox's practice against
            overfitting), and, with several starts, the best start.
            Periodic ones are simulated in steady state. Also passed to the
            start model's fit when it is fitted here. In a grid search leave
            them out: the held-out signals of each split do the validation
            there.

            With or without them, when the training inputs are periodic the
            kept iterate is simulated on 40 new random-phase realisations of
            their spectra (seeded by ``random_state``; peaks no higher than
            the training inputs'), dealt to 8 records of 5 each simulated in
            turn from rest: a period per realisation, the switch between two a
            transient as in a measurement. If it runs away on any (leaves its
            trusted range by more than the range's width, see
            ``range_excursion``), an earlier iterate that does not is kept
            instead (the latest, or the next best on the validation signals),
            with a warning: the data are then few for the model. A PNLSS
            (3, 5, 7) Bouc-Wen model on three realisations of two periods ran
            away on one or two of 14 new realisations of its level for four of
            six data draws (rms errors of 4 to 40 m, 12 to 32 dB, against -76
            dB for the linear start), and on none with the check
            (``benchmarks/bench_small_data.py``). The kept iterate must also
            settle into a periodic steady state on each periodic training
            input repeated from rest, as :meth:`predict` seeks it: the cost
            scores a period after a transient of at most a period, where a
            model that oscillates by itself, its response drifting a little
            each period, costs no more (F-16 decoupled models unstable at
            rest, ``benchmarks/f16_lru.py``: such a model fails the test level
            between two fitted ones).
        X_check : signals or None, default=None
            Inputs measured at the training levels but of other kinds than
            the training inputs (a sine sweep beside multisines, an impact),
            without their outputs: each is simulated from rest, and the
            kept iterate must not run away on any of them either (checked
            as the new realisations are). A random-phase realisation spreads
            its power over the band; a sweep dwells on each resonance in
            turn. An F-16 decoupled model fitted on the multisines of levels
            1, 3, 5 and 7 ran away on the sine sweep of level 7 (and on the
            test level 6's) and on none of the realisations; with those
            levels' sweeps passed here it keeps an earlier iterate, and its
            draw scores the same on the test multisines
            (``benchmarks/f16_lru.py``).
        y_check : signals or None, default=None
            The outputs measured with ``X_check``, when known: the kept
            iterate must then also simulate each check record from rest no
            worse (rms error) than the fit's start does. They refuse only,
            never choose (that would make them validation signals): a
            model far worse than its start on a measured record has jumped
            onto another response near a resonance, or drifted, where its
            range excursion can stay within the runaway bound.
        time_weight : signals or None, default=None
            Non-negative weight of the squared error at each sample, in the
            layout of ``y`` (with n_outputs channels, or one channel for all
            outputs). Only with the time-domain weightings (``weighting``
            None or "relative", which multiplies it).

        Returns
        -------
        self
        """
        X, stage = detach_stage(X)
        X_list, y_list = self._validate_fit_data(X, y)
        self.period_ = self._handed_period(stage)
        # checked before a model is returned: it must not run away on new
        # realisations of the training excitation, and must settle on the
        # training inputs repeated from rest (periodic inputs only)
        check_records = self._check_records(X_check)
        settings = replace(self._fit_settings(), new_inputs=random_phase_inputs(
            X_list, self.period_, random_state=self.random_state),
            training_periods=training_periods(X_list, self.period_), check_records=check_records,
            check_outputs=self._check_outputs(y_check, X_check is not None, check_records))
        weights = self._check_time_weight(time_weight, y_list)
        if self.weighting == "relative":
            weights = relative_weights(y_list, weights)
        val = self._check_validation(X_val, y_val)
        start = self._fit_start(stage, X_list, y_list, val, weights)
        objectives = simulation_objectives(start, X_list, y_list, settings, weights)
        self._set_fit_result(self._fit_from_start(start, objectives, settings, val, X_list))
        self._export(X_list)
        self.n_params_ = self.model_.n_params - self.model_.normalised.n_fixed_params
        self.n_nonlinear_params_ = self.model_.n_nonlinear_params
        return self

    def _normalised_linear(self, linear, X_list, y_list):
        """The fitted linear model ``linear`` (a BLAEstimator) normalised to
        unit-rms inputs, outputs and states on the training signals (a
        ScaledModel without monomials): where the nonlinear fits start."""
        periods = [self.period_ if self._signal_is_periodic(U.shape[0]) else None for U in X_list]
        return normalised_linear_start(linear.A_, linear.B_, linear.C_, linear.D_, X_list, y_list, periods,
                                       linear.model_.input_offset, linear.model_.output_offset)

    def _handed_period(self, stage):
        """``period``, or, when it is None, the period of the Pipeline stage
        this estimator starts from (periodic data stay periodic down the
        Pipeline, as ``fs`` does)."""
        own = check_period(self.period)
        handed = None if stage is None else getattr(stage, "period_", stage.get_params().get("period"))
        if own is not None and handed is not None and own != handed:
            raise ValueError(
                f"period={own} but the Pipeline stage before, {type(stage).__name__}, has "
                f"period={handed}; give both the same period (or leave this one None)."
            )
        return own if own is not None else handed

    def _fit_settings(self):
        return FitSettings(
            period=self.period_, average_periods=self.average_periods, weighting=self.weighting,
            band=self.band, max_iter=self.max_iter, tol=self.tol, n_transient=self.n_transient,
            extrapolation=self.extrapolation, range_margin=self.range_margin,
            stable_at_rest=self.stable_at_rest, verbose=self.verbose,
            n_threads=self._segment_threads(),
        )

    def _segment_threads(self):
        """Threads over the training segments (subclasses with an ``n_jobs``
        for something else keep 1)."""
        return 1

    def _check_time_weight(self, time_weight, y_list):
        if time_weight is None:
            return None
        if self.weighting not in TIME_DOMAIN_WEIGHTINGS:
            raise ValueError(
                f"time_weight is a time-domain weighting, but weighting={self.weighting!r} "
                "weights in frequency; pass one of them (or weighting='relative')."
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

    def _check_records(self, X_check):
        """``X_check`` as a tuple of 2-D inputs (empty when None)."""
        if X_check is None:
            return ()
        U_list, _ = as_signal_list(detach_stage(X_check)[0], name="X_check")
        if any(U.shape[1] != self.n_features_in_ for U in U_list):
            raise ValueError(f"X_check has {U_list[0].shape[1]} input channels but X has {self.n_features_in_}; "
                             "give the check records the training inputs' channels.")
        return tuple(U_list)

    def _check_outputs(self, y_check, has_records, records):
        """``y_check`` as a tuple of 2-D outputs, one per check record
        (``records``: :meth:`_check_records` of ``X_check``, given when
        ``has_records``), or empty when None."""
        if y_check is None:
            return ()
        if not has_records:
            raise ValueError("y_check was given without X_check: pass the check records' inputs as X_check.")
        Y_list, _ = as_signal_list(y_check, name="y_check")
        if len(Y_list) != len(records) or any(Y.shape[0] != U.shape[0] for Y, U in zip(Y_list, records)):
            raise ValueError("y_check must hold one output signal per X_check record, of the same length; got "
                             f"{[Y.shape[0] for Y in Y_list]} samples for {[U.shape[0] for U in records]}.")
        if any(Y.shape[1] != self.n_outputs_ for Y in Y_list):
            raise ValueError(f"y_check has {Y_list[0].shape[1]} output channels but y has {self.n_outputs_}.")
        return tuple(Y_list)

    def _check_validation(self, X_val, y_val):
        if (X_val is None) != (y_val is None):
            raise ValueError("Pass both X_val and y_val, or neither.")
        if X_val is None:
            return None
        Xv, yv, _ = validate_signals(self, X_val, y_val, reset=False)
        if yv[0].shape[1] != self.n_outputs_:
            raise ValueError(f"y_val has {yv[0].shape[1]} outputs but y has {self.n_outputs_}.")
        return Xv, yv

    def _set_fit_result(self, fit):
        rho = np.max(np.abs(np.linalg.eigvals(fit.model.normalised.A)))
        if self.extrapolation != "polynomial" and rho >= 1:
            # The hold bounds the nonlinear term; only a stable A turns that
            # into a bounded state.
            warnings.warn(
                f"The fitted linear part A has spectral radius {rho:.4g} >= 1: holding the "
                "nonlinearity at its trusted range no longer bounds the state. Pass validation "
                "signals (X_val, y_val) or fewer iterations (max_iter).", UserWarning, stacklevel=4,
            )
        rest = fit.model.normalised.radius_at_rest()
        if rest >= 1.0:
            warnings.warn(
                f"The fitted model is unstable at rest (its state equation linearised at rest has spectral "
                f"radius {rest:.6f} >= 1): with no input, or one below the levels it was fitted at, it "
                "oscillates by itself. Pass stable_at_rest=True to refuse such steps (the start must be "
                "stable at rest).", UserWarning, stacklevel=4,
            )
        if fit.new_input_runaway is not None:
            ranking = "the latest" if fit.validation_history is None else "the best on the validation signals"
            warnings.warn(fit.new_input_runaway.message(ranking), UserWarning, stacklevel=4)
        self.model_ = fit.model
        self.n_iter_ = fit.n_iter
        self.best_iteration_ = fit.best_iteration
        self.cost_history_ = fit.cost_history
        if fit.validation_history is not None:
            self.validation_history_ = fit.validation_history

    def _predict_signal(self, U, periodic):
        try:
            return self.model_.simulate(U, self.period_ if periodic else None)
        except DivergenceError as exc:
            raise DivergenceError(
                f"{type(self).__name__}.predict: {exc}; the input X drives the model far "
                "outside the range it was fitted on (larger amplitude or other "
                "frequencies than the training data).", sample=exc.sample,
            ) from None

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
        >>> from scipy.signal import lfilter
        >>> X, _ = multisine(128, fs=100.0, f_band=(1, 40), n_periods=2, n_realizations=2, random_state=0)
        >>> # steady state of v(t) = 0.6 v(t-1) + 0.5 u(t-1), then y = v + 0.2 v^2
        >>> v = np.stack([np.tile(lfilter([0.0, 0.5], [1, -0.6], np.tile(x[:128, 0], 3))[-128:], 2)
        ...               for x in X])[..., None]
        >>> model = PNLSSRegressor(1, degrees=(2,), period=128, max_iter=5).fit(X, v + 0.2 * v**2)
        >>> bool(model.range_excursion(X).max() <= model.range_margin)
        True
        >>> bool(model.range_excursion(3 * X).max() > 1)
        True
        """
        check_is_fitted(self)
        X_list, _, _ = validate_signals(self, X, reset=False, min_samples=1)
        return np.array([
            self.model_.range_excursion(U, self.period_ if self._signal_is_periodic(U.shape[0]) else None)
            for U in X_list
        ])

    def _export(self, X_list):
        """The fitted attributes in the user's units (``A_, B_, C_, D_``
        here; the subclass adds its nonlinear blocks). Returns the model in
        user units."""
        user = self.model_.in_user_units()
        self.A_, self.B_, self.C_, self.D_ = user.A, user.B, user.C, user.D
        return user
