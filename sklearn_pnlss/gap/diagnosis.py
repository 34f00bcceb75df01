"""GapDiagnosis: where a physical simulator misses the measurements, which
unmodelled effect explains it, and by how much adding it shrinks the gap."""
import time
import warnings
from dataclasses import replace
from numbers import Integral, Real

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from ..physics.oscillator import Oscillator
from ..utils.parameters import Interval, validates_parameters
from ..utils.threads import one_blas_thread
from ..utils.validation import as_signal_list, check_period
from .fitting.black_box import branch_opinions
from .fitting.calibrate import meaningful_ftol, parameter_covariance
from .candidates.clues import read_clues
from .verdict.decision import decide
from .candidates.effects import NOMINAL_PARAMETERS, Recalibration, Scales, default_effects, make_effect
from .verdict.noise_floor import (estimate_noise, non_excited_noise, repeated_input_noise,
                                  residual_noise, unsettled_signals)
from .report import GapReport
from .fitting.simulate import SignalSet, detect_period, measured_starts, simulate_signals
from .readings import misfit, signal_derivative
from .where import locate_gap
from .stages import BLACK_BOX, STAGES, Fitting
from .settings import SETTINGS

__all__ = ["GapDiagnosis"]


def _siso(X, name, min_samples=16):
    signals, _ = as_signal_list(X, name=name, min_samples=min_samples)
    if signals[0].shape[1] != 1:
        raise ValueError(
            f"{name} must have one channel (the oscillator has one input force and one "
            f"displacement output), got {signals[0].shape[1]}."
        )
    return [s[:, 0] for s in signals]


def _check_pairs(u_list, y_list, xname, yname):
    if len(u_list) != len(y_list):
        raise ValueError(f"{xname} holds {len(u_list)} signals but {yname} holds {len(y_list)}.")
    for i, (u, y) in enumerate(zip(u_list, y_list)):
        if u.size != y.size:
            raise ValueError(f"{xname}[{i}] has {u.size} samples but {yname}[{i}] has {y.size}.")


class GapDiagnosis(BaseEstimator):
    """Diagnose the gap between a physical simulator and measurements.

    ``fit`` fits every candidate effect, added to the nominal simulator, to
    the measured training signals by simulation error (and a black-box
    decoupled PNLSS model of the same data); ``report`` scores them on
    validation signals, says whether there is a significant gap, where it
    lies, which effect explains it and how far it shrinks.

    Parameters
    ----------
    nominal : Oscillator
        The user's physical simulator (mass, damping, stiffness and its
        force elements).
    fs : float
        Sampling rate of the signals, Hz.
    period : int, default=None
        Samples per period of periodic excitations (a UserWarning names the
        period when the training inputs repeat and this is None).  A signal whose length
        is a multiple of it is periodic steady state (simulated
        periodically); any other signal starts from rest.  Periodic signals
        of two periods or more give the noise floor; without them it is
        read from repeated inputs or from the lines the input does not
        excite (see :mod:`sklearn_pnlss.gap.verdict.noise_floor`).
    effects : list of str or ForceElement, default=None
        Candidate effects: names from :func:`default_effects` and/or the
        user's own force elements (every parameter of which is fitted from
        its given value).  None: all built-in effects.
    free_nominal : bool or list of str, default=True
        Nominal parameters refitted together with every candidate effect:
        True for all of ``"mass"``, ``"damping"`` and ``"stiffness"``, a list
        for those only, False for none (the nominal is then taken as exact).
        A nominal read off measurements is only approximately right, and an
        effect it lacks is partly absorbed in its linear parameters already
        (the stiffness of a BLA carries the average hardening of a cubic
        spring): with those fixed no single effect fits.  The report gives
        the refitted values beside the effect's.  ``recalibration`` (the
        freed parameters alone, no new physics) stays a candidate and is
        preferred when it explains as much.
    offsets : bool, default=True
        Treat constant offsets of the measured channels as the sensors',
        not the structure's: each input signal is taken less its mean (a
        shaker applies no static force; a force cell's zero drifts), and
        every model, the nominal included, is granted each output signal's
        best constant offset when fitted and scored.  False when the
        recorded force has a true static part.
    oversampling : int, default=20
        Integration rate over ``fs`` of every reported simulation (the
        benchmark's 20); the output is FIR-decimated by its prime factors.
    fit_oversampling : int, default=5
        Integration rate over ``fs`` while fitting the candidates, with the
        nominal model's discretisation error carried over (see
        :meth:`SignalSet.coarse`); the candidates within ``SETTINGS.contention_db``
        of the best are then refined at ``oversampling``, and every fit is
        scored there.
    black_box : bool, default=True
        Also fit a decoupled PNLSS model to tell how much of the gap any
        model can close, and read its branches as a second opinion.
    significance : float, default=1e-3
        Level of the test of the gap against the noise floor.
    max_nfev : int, default=20
        Trust-region iterations per candidate.
    n_jobs : int, default=None
        Candidates fitted in parallel (threads; the integrator releases the
        GIL).
    random_state : int, RandomState instance or None, default=None
        Seed of the black-box model's random starts.
    verbose : int, default=0
        Print progress: each candidate as soon as it is fitted (``3/12
        done, backlash: ...`` with its training error, simulations and
        time), the black box included.

    Attributes
    ----------
    scales_ : Scales
        Force, displacement, velocity and duration scales of the data.
    noise_ : NoiseFloor or None
        Noise floor of the training signals: from their period-to-period
        spread, else from signals of the same input, else from the best
        model's residual at the lines the input does not excite (its
        ``source`` and ``detail`` say which); None when the data give none.
    fits_ : list of EffectFit
        The fitted candidates, in the order of ``effects``; when a channel
        delay is found and the nominal's refit with it moves a parameter,
        that refit is ``recalibration`` and ``input_delay`` is left out.
    combinations_ : list of EffectFit
        The forward selection's fits: the best candidate with a second
        effect, then with a third, each kept while it adds to the one
        before on training (see :func:`sklearn_pnlss.gap.stages.added_effects`);
        empty when the best candidate alone explains the training data.
    black_box_ : DecoupledPNLSSRegressor or None
    black_box_branches_ : list of dict
        Reading of each black-box branch on the training signals (see
        :func:`sklearn_pnlss.gap.fitting.black_box.branch_opinions`).
    delay_ : ChannelDelay or None
        The delay between the force and displacement channels the training
        data show (:class:`~sklearn_pnlss.gap.results.ChannelDelay`:
        ``delay_s``, seconds; ``gain_db``, how much it improves the fit it
        was found on; ``found_on``, that fit), fitted with every candidate;
        None when no fit gains enough from it.
    train_gap_db_ : float
        Mean square training gap of the nominal simulator, dB.
    fit_time_ : float
        Seconds spent in ``fit``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.gap import GapDiagnosis
    >>> from sklearn_pnlss.physics import Oscillator, CubicStiffness
    >>> from sklearn_pnlss.signals import multisine
    >>> X, _ = multisine(1024, fs=750.0, rms=50.0, n_periods=2, n_realizations=1,
    ...                  random_state=0)
    >>> nominal = Oscillator(2.0, 10.0, 5e4)
    >>> real = Oscillator(2.0, 10.0, 5e4, forces=(CubicStiffness(1e8),))
    >>> y = real.simulate(X[0, :, 0], fs=750.0, periodic=True, noise_rms=2e-6,
    ...                   random_state=0)
    >>> diag = GapDiagnosis(nominal, fs=750.0, period=1024,
    ...                     effects=["cubic_stiffness", "quadratic_damping"],
    ...                     black_box=False).fit(X, y[None, :, None])
    >>> diag.report(X, y[None, :, None]).best_effect
    'cubic_stiffness'
    """

    _parameter_constraints = {
        "nominal": [Oscillator],
        "fs": [Interval(Real, 0, None, closed="neither")],
        "period": [Interval(Integral, 2, None, closed="left"), None],
        "effects": [list, tuple, None],
        "free_nominal": ["boolean", list, tuple],
        "offsets": ["boolean"],
        "oversampling": [Interval(Integral, 1, None, closed="left")],
        "fit_oversampling": [Interval(Integral, 1, None, closed="left")],
        "black_box": ["boolean"],
        "significance": [Interval(Real, 0, 1, closed="neither")],
        "max_nfev": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Integral, None],
        "random_state": ["random_state"],
        "verbose": ["verbose"],
    }

    def __init__(self, nominal, *, fs, period=None, effects=None, free_nominal=True,
                 offsets=True, oversampling=20, fit_oversampling=5, black_box=True, significance=1e-3,
                 max_nfev=20, n_jobs=None, random_state=None, verbose=0):
        self.nominal = nominal
        self.fs = fs
        self.period = period
        self.effects = effects
        self.free_nominal = free_nominal
        self.offsets = offsets
        self.oversampling = oversampling
        self.fit_oversampling = fit_oversampling
        self.black_box = black_box
        self.significance = significance
        self.max_nfev = max_nfev
        self.n_jobs = n_jobs
        self.random_state = random_state
        self.verbose = verbose

    # ------------------------------------------------------------------
    def _signal_set(self, u_list, y_list):
        """The measured signals as simulated: each periodic one's steady
        state searched from the state its measurement (``y_list``, less
        its offsets) starts in; and the measured velocities."""
        signals = SignalSet.from_signals(u_list, self.period, self.fs, self.oversampling)
        velocity = [signal_derivative(y, self.fs, P, self.period) for y, P in zip(y_list, signals.n_periods)]
        signals.starts = measured_starts(y_list, velocity, signals.n_periods, self.period)
        return signals, velocity

    def _candidates(self):
        names = default_effects() if self.effects is None else list(self.effects)
        if not names:
            raise ValueError("effects is empty; pass None for all built-in effects.")
        effects = [make_effect(e) for e in names]
        seen = set()
        for e in effects:
            if e.name in seen:
                raise ValueError(f"effect {e.name!r} is listed twice in effects.")
            seen.add(e.name)
        return effects

    def _free_nominal(self):
        """The nominal parameters ``free_nominal`` names, checked."""
        if isinstance(self.free_nominal, (bool, np.bool_)):
            return NOMINAL_PARAMETERS if self.free_nominal else ()
        unknown = [p for p in self.free_nominal if p not in NOMINAL_PARAMETERS]
        if unknown or not self.free_nominal:
            raise ValueError(f"free_nominal must be True, False or a non-empty list of {list(NOMINAL_PARAMETERS)}; "
                             f"got {self.free_nominal!r}.")
        return tuple(p for p in NOMINAL_PARAMETERS if p in self.free_nominal)

    def _log(self, text):
        if self.verbose:
            print(f"[GapDiagnosis] {text}", flush=True)

    @validates_parameters
    def fit(self, X, y):
        """Fit every candidate effect (and the black box) to training signals.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, 1), or list of signals
            Measured input force.
        y : array-like of shape (n_signals, n_samples, 1), or list of signals
            Measured displacement.

        Returns
        -------
        self : GapDiagnosis
        """
        start = time.perf_counter()
        self.period_ = check_period(self.period)
        u_list, y_list = _siso(X, "X"), _siso(y, "y")
        _check_pairs(u_list, y_list, "X", "y")
        u_list = self._inputs(u_list)
        u_list, y_list = self._settled(u_list, y_list)
        effects = self._candidates()
        repeats = self.period_ is None and self._warn_if_periodic(u_list)
        # The steady-state starts, the force-law starts and the black box
        # (which has no constant term) read the measured motion, which a
        # sensor's offset would shift.
        y_centred = self._outputs(y_list)
        train, velocity_list = self._signal_set(u_list, y_centred)

        y_all = np.concatenate(y_list)
        u_all = np.concatenate(u_list)
        velocity = np.concatenate(velocity_list)
        if np.std(u_all) == 0 or np.std(y_all) == 0:
            raise ValueError("X and y must not be constant: a diagnosis needs an excited response.")
        self.scales_ = Scales(
            force=float(np.sqrt(np.mean(u_all**2))),
            displacement=float(np.sqrt(np.mean(y_all**2))),
            velocity=float(np.sqrt(np.mean(velocity**2))),
            duration=max(u.size for u in u_list) / self.fs,
            u_peak=float(np.max(np.abs(u_all))),
            fs=float(self.fs),
        )
        # The floors the data give before any fit; without them the floor
        # is read from the fitted models' residuals once they are fitted.
        self.noise_ = estimate_noise(y_list, self.period)
        if self.noise_ is None:
            self.noise_ = repeated_input_noise(u_list, y_list, self.period, self.fs)
        y_nominal = simulate_signals(self.nominal, train)
        if self.period_ is None and not repeats:
            # (fit is wrapped by the parameter check: one frame more)
            self._warn_if_steady_state(u_list, y_list, y_nominal, "training", stacklevel=4)
        self.train_gap_db_ = float(10 * np.log10(np.mean(np.concatenate(
            [misfit(a, b, self.offsets) for a, b in zip(y_nominal, y_list)]) ** 2)))

        clues = read_clues(self.nominal, u_list, y_centred, y_nominal, train.n_periods, self.period_, self.fs)
        self._log(f"fitting {len(effects)} candidates{' and the black box' if self.black_box else ''} "
                  f"on {len(u_list)} signals")
        settings = dict(ftol=meaningful_ftol(self.noise_, y_all.size), offsets=self.offsets,
                        noise_variance=None if self.noise_ is None else self.noise_.variance)
        free = self._free_nominal()
        run = Fitting(self, u_list, y_list, y_centred, y_nominal, train,
                      train.coarse(self.fit_oversampling, self.nominal), clues, effects,
                      Recalibration(free) if free else None, settings)
        for stage in STAGES:
            stage(run)
        effects, done, self.delay_ = run.effects, run.done, run.delay
        self.combinations_ = run.combinations
        self.fits_ = [done[e.name] for e in effects]
        self.black_box_, self.black_box_branches_ = done.get(BLACK_BOX), []
        if self.black_box_ is not None:
            # Read on the training signals: the branches' own range.
            self.black_box_branches_ = branch_opinions(self.black_box_, u_list, y_list, velocity_list,
                                                       self.scales_)
        if self.noise_ is None:
            self.noise_ = self._model_noise_floor(train, u_list, y_list, y_nominal)
            if self.noise_ is not None:
                self._log(f"noise floor {10 * np.log10(self.noise_.variance):.2f} dB: {self.noise_.detail}")
        # Kept for report's "where" analysis (distortion level, drift, gap
        # against input level); passed on explicitly, read by no other module.
        self._train = (u_list, y_list)
        self._train_nominal = y_nominal
        self.fit_time_ = time.perf_counter() - start
        return self

    def _settled(self, u_list, y_list):
        """The training signals in steady state; the others
        (``unsettled_signals_``) are left out, with a warning."""
        self.unsettled_signals_ = unsettled_signals(y_list, self.period_)
        if not self.unsettled_signals_:
            return u_list, y_list
        which = ", ".join(map(str, self.unsettled_signals_))
        one = len(self.unsettled_signals_) == 1
        warnings.warn(
            f"Training signal{'' if one else 's'} {which} never settle{'s' if one else ''}: "
            f"{'its' if one else 'their'} periods differ {SETTINGS.unsettled_ratio:g} times (power) or more than the "
            f"quietest other signal's periods do (a chaotic response, a record started before the transient "
            f"died, or a structure that changed during it). No periodic simulation can follow such a signal, "
            f"and its spread is not the sensor's noise: left out of the fits and the noise floor.",
            UserWarning, stacklevel=4)  # fit is wrapped by the parameter check
        keep = [i for i in range(len(u_list)) if i not in self.unsettled_signals_]
        return [u_list[i] for i in keep], [y_list[i] for i in keep]

    def _inputs(self, u_list):
        """The input signals, less their means with ``offsets``."""
        return [u - u.mean() for u in u_list] if self.offsets else u_list

    def _outputs(self, y_list):
        """The measured displacements, less their means with ``offsets``."""
        return [y - y.mean() for y in y_list] if self.offsets else y_list

    def _warn_if_periodic(self, u_list):
        """Warn when the training inputs repeat themselves and no period was
        given: steady-state data would be simulated from rest (a transient
        the measurement does not hold) and their periods would give no
        noise floor.  Whether it warned."""
        found = detect_period(u_list)
        if found is None:
            return False
        n_periods = [u.size / found for u in u_list]
        whole = all(abs(p - round(p)) < 1e-9 for p in n_periods)
        warnings.warn(
            f"The training inputs look periodic: they repeat every {found} samples "
            f"({found / self.fs:.4g} s"
            + (f", {'/'.join(str(round(p)) for p in sorted(set(n_periods)))} periods per signal" if whole else "")
            + f"), but period=None, so every signal is simulated from rest and no noise floor is read from "
            f"its periods. If they are in steady state, pass period={found}.",
            UserWarning, stacklevel=4)
        return True

    def _warn_if_steady_state(self, u_list, y_list, y_nominal, which, stacklevel):
        """Warn about signals that look like one steady-state period while
        period=None simulates them from rest.

        A single period does not repeat, so the input cannot tell; the
        response can.  The nominal simulated as that one period in steady
        state differs from its simulation from rest by the start-up
        transient ``d``; the measurement holds it (as a steady-state record
        does) when the misfit from rest projects onto ``d`` with a
        coefficient of at least ``SETTINGS.steady_state_share`` and ``d`` is not
        negligible (a tenth of the misfit's power).  A record from rest
        projects near zero: the model's other errors do not ring like its
        own free response.
        """
        suspects = []
        for i, (u, y, y_rest) in enumerate(zip(u_list, y_list, y_nominal)):
            # the signal as one steady-state period of itself
            one_period = SignalSet.from_signals([u], u.size, self.fs, self.oversampling)
            y_steady = simulate_signals(self.nominal, one_period)[0]
            d, r = y_steady - y_rest, y - y_rest
            d, r = d - d.mean(), r - r.mean()
            power_d, power_r = d @ d, r @ r
            if power_d > 0.1 * power_r and r @ d > SETTINGS.steady_state_share * power_d:
                suspects.append(i)
        if suspects:
            sizes = sorted({u_list[i].size for i in suspects})
            warnings.warn(
                f"The {which} signals {suspects} look like steady-state periods (at their start the response "
                f"is already in full swing), but period=None, so they are simulated from rest and the "
                f"start-up transient counts as gap. If each is one period of a periodic excitation, pass "
                + (f"period={sizes[0]}." if len(sizes) == 1 else "a period that divides their lengths."),
                UserWarning, stacklevel=stacklevel)

    def _model_noise_floor(self, train, u_list, y_list, y_nominal):
        """Noise floor from the residuals of the nominal, the fitted
        candidates and the black box at the lines the training inputs do
        not excite (see :func:`~sklearn_pnlss.gap.verdict.noise_floor.non_excited_noise`):
        the floor of data that repeat no period."""
        sims = self._simulate_fits(train)
        simulations = {"nominal": y_nominal, **{f.effect.name: s for f, s in zip(self.fits_, sims)}}
        if self.black_box_ is not None:
            bb = [self._black_box_predict(u) for u in u_list]
            simulations["black box"] = None if any(b is None for b in bb) else bb
        return non_excited_noise(u_list, y_list, simulations, self.period_, self.fs)

    def _simulate_fit(self, fit, signals, theta=None):
        """The fitted candidate's simulation of ``signals`` (at ``theta``,
        default its fitted one); None where it diverges or is not physical."""
        try:
            osc, transform, _ = fit.effect.simulator(fit.theta if theta is None else theta, self.nominal,
                                                     self.scales_)
            return simulate_signals(osc, signals, transform)
        except (ValueError, FloatingPointError):
            return None

    def _simulate_fits(self, signals, fits=None):
        """Every fitted candidate's (or ``fits``') simulation of
        ``signals``, in parallel threads (None for one that diverges)."""
        with one_blas_thread():
            return Parallel(n_jobs=self.n_jobs, prefer="threads")(
                delayed(self._simulate_fit)(f, signals) for f in (self.fits_ if fits is None else fits))

    def _black_box_predict(self, u):
        """The black box's simulation of one signal; None where it leaves its
        fitted range and diverges (a black box extrapolates poorly)."""
        try:
            return np.asarray(self.black_box_.predict(u[:, None]))[:, 0]
        except ValueError:
            return None

    def _sensitive_signals(self, decision, val, y_effects, noise):
        """Validation signals the best candidate cannot pin down: with its
        parameters drawn from what the training data determine (their
        covariance, :func:`parameter_covariance`; ``SETTINGS.sensitivity_draws``
        draws), its simulation moves by more than the noise on average.

        A strongly nonlinear response can be chaotic or pass a jump (several
        coexisting steady states): then the true model with its parameters
        moved within their standard errors simulates another orbit, and
        simulation error on that signal says nothing about the model.  Such
        signals are left out of the closure (the report names them); the
        others decide, or, when every signal moves, the one that moves
        least.  The noise's variance sets the covariance, so a
        candidate that misses the data is not excused by its own misfit.
        (Measured on the benchmark's stiffer cubic spring, 1e8 N/m^3: the
        draws move the multisine's simulation by a thousandth of the noise
        power, the sweep's, through its jump, by a ninth; both are kept.)
        """
        if noise is None or not decision.significant:
            return []
        best = next(i for i, f in enumerate(self.fits_) if f.effect.name == decision.ranking[0].name)
        fit = self.fits_[best]
        if y_effects[best] is None or not fit.effect.n_params:
            return []
        cov = parameter_covariance(fit, self.scales_, noise)
        rng = check_random_state(self.random_state)
        lower, upper = fit.effect.bounds
        draws = [np.clip(rng.multivariate_normal(fit.theta, cov, check_valid="ignore"), lower, upper)
                 for _ in range(SETTINGS.sensitivity_draws)]
        with one_blas_thread():
            moved = Parallel(n_jobs=self.n_jobs, prefer="threads")(
                delayed(self._simulate_fit)(fit, val, theta) for theta in draws)
        moved = [m for m in moved if m is not None]
        if not moved:
            return []
        change = [np.mean([np.mean((m[i] - y_effects[best][i]) ** 2) for m in moved]) for i in range(len(val.u))]
        sensitive = [i for i, c in enumerate(change) if c > noise.variance]
        if len(sensitive) == len(change):
            # Every signal moves: the verdict rests on the one that moves
            # least (a cubic spring of 1e9 N/m^3 with the nominal refitted:
            # its multisine moves -53 dB, its sweep just above the noise).
            sensitive.remove(int(np.argmin(change)))
        return sensitive

    def _nominal_moves(self, fit):
        """Relative change of each freed nominal parameter in ``fit``."""
        return {name: float(fit.physical[name] / getattr(self.nominal, name) - 1)
                for name in self._free_nominal() if name in fit.physical and getattr(self.nominal, name)}

    def _recalibrated(self, decision):
        """Relative change of each freed nominal parameter in the chosen
        candidate's fit (``recalibration`` included: the verdict says which
        parameter was off; the last added effect's combination when effects
        were added), and the channel delay fitted with it, in seconds;
        empty when nothing was freed."""
        name = decision.added_effects[-1].name if decision.added_effects else decision.best_effect
        chosen = next((f for f in self.fits_ + self.combinations_ if f.effect.name == name), None)
        if chosen is None:
            return {}
        moved = self._nominal_moves(chosen)
        if "delay_s" in chosen.physical and chosen.effect.name != "input_delay":
            moved["delay_s"] = float(chosen.physical["delay_s"])  # the measurement chain's, not relative
        return moved

    def report(self, X_val, y_val):
        """Score the candidates on validation signals and explain the gap.

        Parameters
        ----------
        X_val, y_val : signals as in :meth:`fit`
            Validation signals never used in ``fit``, e.g. one steady-state
            multisine period and a swept sine from rest.

        Returns
        -------
        GapReport
        """
        check_is_fitted(self, "fits_")
        u_list, y_list = _siso(X_val, "X_val"), _siso(y_val, "y_val")
        _check_pairs(u_list, y_list, "X_val", "y_val")
        u_list = self._inputs(u_list)
        val, _ = self._signal_set(u_list, self._outputs(y_list))
        y_nominal = simulate_signals(self.nominal, val)
        if self.period_ is None:
            self._warn_if_steady_state(u_list, y_list, y_nominal, "validation", stacklevel=3)

        y_effects = self._simulate_fits(val)
        y_black_box = None
        if self.black_box_ is not None:
            y_black_box = [self._black_box_predict(u) for u in u_list]
        noise = self.noise_
        if noise is None and y_black_box is not None:
            # No floor from the training data: what the black box achieves
            # on these signals is the yardstick.
            grid = self.period_ or max(u.size for u in self._train[0])
            noise = residual_noise(y_list, y_black_box, grid)
        y_combinations = self._simulate_fits(val, self.combinations_)
        decision = decide(self.fits_, y_list, y_nominal, y_effects, y_black_box, noise, self.significance,
                          self.offsets, self.combinations_, y_combinations)
        sensitive = self._sensitive_signals(decision, val, y_effects, noise)
        if sensitive:
            keep = [i for i in range(len(u_list)) if i not in sensitive]

            def pick(signals):
                return None if signals is None else [signals[i] for i in keep]

            decision = decide(self.fits_, pick(y_list), pick(y_nominal), [pick(y) for y in y_effects],
                              pick(y_black_box), noise, self.significance, self.offsets, self.combinations_,
                              [pick(y) for y in y_combinations])
            decision = replace(decision, sensitive_signals=sensitive)
        decision = replace(decision, recalibrated=self._recalibrated(decision))
        u_train, y_train = self._train
        where = locate_gap(self.nominal, u_list, y_list, y_nominal, val.n_periods, fs=self.fs,
                           period=self.period_, noise=noise, significance=self.significance,
                           u_train=u_train, y_train=y_train, y_train_nominal=self._train_nominal)
        return GapReport(decision=decision, where=where, scales=self.scales_, noise=noise,
                         black_box=self.black_box_, fits=self.fits_, opinions=self.black_box_branches_,
                         unsettled=self.unsettled_signals_)
