"""Simulate an oscillator on measured input signals, the benchmark way.

Each signal is either steady-state periodic (its length is ``P`` periods) or
starts from rest.  A periodic signal is simulated over one period until
steady state and repeated, unless the oscillator is time-varying (stiffness
drift): then the steady state of the oscillator frozen at ``t = 0`` is the
start, and the ``P`` periods are integrated one after the other.

The steady-state search of a measured periodic signal starts from the state
the measurement shows at its period start (:attr:`SignalSet.starts`), not
from rest.  Where several steady states coexist (a stiffening spring driven
above its resonance), the one the experiment settled on is an unknown of
the experiment, not of the model: started from rest, the right model can
settle on the other one, and no parameter change brings it back.
"""
from dataclasses import dataclass

import numpy as np
from sklearn.utils import check_random_state

from ...physics.oscillator import STATE_Z, band_limited_noise
from ...physics.resampling import decimate_columns, decimate_fir, upsample_fft
from ...utils.threads import each_in_threads
from ...utils.validation import is_periodic

__all__ = ["SignalSet", "simulate_signals", "simulate_sensitivities", "measured_starts", "prime_factors",
           "detect_period"]


def prime_factors(n):
    """Decimation chain for an oversampling factor: its prime factors,
    smallest first (20 -> (2, 2, 5), as the benchmark's chain)."""
    factors, d = [], 2
    while n > 1:
        while n % d == 0:
            factors.append(d)
            n //= d
        d += 1
    return tuple(factors) or (1,)


def detect_period(signals, *, min_period=16, threshold=0.99):
    """The period, in samples, of signals that repeat themselves, or None.

    A signal repeats with lag ``L`` when its normalised autocorrelation
    there, ``sum x[n] x[n + L]`` over the root of the two overlapping parts'
    energies, exceeds ``threshold`` (0.99: the periods differ by about
    -17 dB of the signal, a measured force's noise included).  The first
    run of lags above it, between ``min_period`` and half the length, is
    taken and the lag at its peak returned (a smooth signal stays above the
    threshold for a few lags around its period).  A random-phase multisine
    has an autocorrelation of the order of one over the root of its number
    of lines away from multiples of its period, noise and sweeps one that
    never comes back; a single period tells nothing.

    Parameters
    ----------
    signals : list of ndarray (n_samples_i,)
    min_period : int, default=16
    threshold : float, default=0.99

    Returns
    -------
    period : int or None
        The smallest period found over the signals that repeat.
    """
    found = []
    for x in signals:
        x = np.asarray(x, float) - np.mean(x)
        n = x.size
        if n < 2 * min_period:
            continue
        spec = np.fft.rfft(x, 2 * n)  # zero-padded: the linear autocorrelation
        ac = np.fft.irfft(np.abs(spec) ** 2, 2 * n)[:n]
        energy = np.concatenate([[0.0], np.cumsum(x**2)])
        lags = np.arange(min_period, n // 2 + 1)
        # energies of x[:n-L] and x[L:]
        head, tail = energy[n - lags], energy[n] - energy[lags]
        r = ac[lags] / np.sqrt(np.maximum(head * tail, 1e-300))
        above = np.flatnonzero(r > threshold)
        if above.size == 0:
            continue
        run_end = above[0]
        while run_end + 1 < r.size and r[run_end + 1] > threshold:
            run_end += 1
        found.append(int(lags[above[0] + np.argmax(r[above[0]:run_end + 1])]))
    return min(found) if found else None


@dataclass
class SignalSet:
    """Input signals with their periodicity and their inputs at the
    integration rate (computed once, reused by every simulation).

    Attributes
    ----------
    u : list of ndarray (n_samples_i,)
    n_periods : list of int
        Periods of each signal (0: starts from rest).
    period : int or None
    fs : float
    oversampling : int
    decimation : tuple of int
    starts : list of (float, float) or None, default=None
        Displacement and velocity at the start of each periodic signal
        (None for a signal, or for all: from rest), where its steady-state
        search begins; see :func:`measured_starts`.
    """

    u: list
    n_periods: list
    period: int
    fs: float
    oversampling: int
    decimation: tuple
    starts: list = None

    def __post_init__(self):
        self.correction = None
        self.u_fine = []
        for u, P in zip(self.u, self.n_periods):
            if P:
                self.u_fine.append(upsample_fft(u[: self.period], self.oversampling, periodic=True))
            else:
                self.u_fine.append(upsample_fft(u, self.oversampling, periodic=False))

    @classmethod
    def from_signals(cls, u_list, period, fs, oversampling, decimation=None, starts=None):
        n_periods = [u.size // period if is_periodic(u.size, period) else 0 for u in u_list]
        decimation = prime_factors(oversampling) if decimation is None else tuple(decimation)
        return cls(list(u_list), n_periods, period, float(fs), int(oversampling), decimation, starts)

    def coarse(self, oversampling, nominal, transform=None):
        """The same signals integrated at a lower rate, corrected by the
        nominal model's discretisation error.

        The difference between the nominal simulation at this set's rate and
        at ``oversampling`` is added to every coarse simulation: what remains
        is the change of that error due to an effect, second order in the
        effect's size.  At 5 times the data rate the nominal Bouc-Wen error
        is -44 dB and the corrected one falls well below the noise, for a
        fourth of the cost.  ``transform``: the nominal's input transform
        (a channel delay it is refitted with), if any.
        """
        if oversampling >= self.oversampling:
            return self
        out = SignalSet(self.u, self.n_periods, self.period, self.fs, int(oversampling),
                        prime_factors(oversampling), self.starts)
        fine = simulate_signals(nominal, self, transform)
        out.correction = [f - c for f, c in zip(fine, simulate_signals(nominal, out, transform))]
        return out

    def without_correction(self):
        """This set with no correction added to its simulations."""
        return self.with_correction(None)

    def with_correction(self, correction):
        """This set with another correction (shares the inputs)."""
        out = self.subset(range(len(self.u)))
        out.correction = correction
        return out

    def subset(self, index):
        """The signals at ``index`` (inputs at the integration rate shared)."""
        out = SignalSet.__new__(SignalSet)
        out.u = [self.u[i] for i in index]
        out.n_periods = [self.n_periods[i] for i in index]
        out.u_fine = [self.u_fine[i] for i in index]
        out.correction = None if self.correction is None else [self.correction[i] for i in index]
        out.starts = None if self.starts is None else [self.starts[i] for i in index]
        out.period, out.fs = self.period, self.fs
        out.oversampling, out.decimation = self.oversampling, self.decimation
        return out


def _frozen(osc):
    """The oscillator at t = 0: its time-varying elements left out."""
    return osc.with_forces([f for f in osc.forces if not f.time_varying])


def _continuation_state(osc, frozen_state):
    """The integrator state of ``osc`` from the steady state of its frozen
    version: time-varying elements start with their states (clocks) at zero;
    the integrator recomputes every rate from the equation of motion."""
    nz = osc.n_internal_states
    state = np.zeros(STATE_Z + 2 * nz)
    state[:STATE_Z] = frozen_state[:STATE_Z]
    j = jf = 0
    for f in osc.forces:
        for _ in range(f.n_states):
            if not f.time_varying:
                state[STATE_Z + j] = frozen_state[STATE_Z + jf]
                jf += 1
            j += 1
    return state


# Steady state: settled when a period ends within this fraction of its peak
# state of where it started (noise sits near 1e-2), and at most this many
# periods, so that a lightly damped trial point cannot stall a fit.  With
# Newton shooting any stable structure settles in about ten; a trial point
# of a fit that has not settled in FIT_MAX_PERIODS is running away (a
# hysteresis whose loop grows without bound), and its misfit says so.
STEADY_TOL = 1e-9
MAX_PERIODS = 30
FIT_MAX_PERIODS = 15


def _repeats(y, n_periods):
    """Whether a record's last period repeats its first: settled, so that
    its decimation is circular (a drifting or unsettled record's is not)."""
    periods = y.reshape(n_periods, -1)
    return np.max(np.abs(periods[-1] - periods[0])) <= 1e-6 * np.max(np.abs(y))


def measured_starts(y_list, velocity_list, n_periods, period):
    """Displacement and velocity each periodic record shows at its period
    start, averaged over its periods (None for a record from rest).

    Parameters
    ----------
    y_list, velocity_list : list of ndarray (n_samples_i,)
        Measured displacement (less a sensor's offset) and its derivative.
    n_periods : list of int
    period : int or None

    Returns
    -------
    starts : list of (float, float) or None
    """
    return [(float(np.mean(y[::period][:P])), float(np.mean(v[::period][:P]))) if P else None
            for y, v, P in zip(y_list, velocity_list, n_periods)]


def _steady(osc, u_fine, fs_fine, max_periods=MAX_PERIODS, max_abs=None, start=None):
    """The periodic steady state, searched from ``start`` (displacement and
    velocity; internal states at zero), else from rest."""
    initial = None
    if start is not None:
        initial = np.zeros(STATE_Z + 2 * osc.n_internal_states)
        initial[:2] = start  # internal states at zero; rates follow from the equation of motion
    return osc.simulate_fine(u_fine, fs=fs_fine, periodic=True, tol=STEADY_TOL, max_periods=max_periods,
                             warn=False, max_abs=max_abs, initial_state=initial)


def _fine_response(osc, u_fine, P, fs_fine, transform, max_periods=MAX_PERIODS, max_abs=None, start=None,
                   record=False):
    """Displacement at the integration rate, whether it is periodic (its
    decimation circular), the steady state it repeats (the integrator's
    state at its period start; None for a signal from rest or a
    time-varying oscillator) and how many times the displacement repeats
    over the signal (a steady state's one period is decimated once, then
    repeated: decimating the whole record cost a third of a fit's trial
    simulation)."""
    periodic = P > 0
    if transform is not None:
        u_fine = transform(u_fine, fs_fine, periodic)
    if not periodic:
        return osc.simulate_fine(u_fine, fs=fs_fine, periodic=False, max_abs=max_abs).y, False, None, 1
    if not osc.time_varying:
        steady = _steady(osc, u_fine, fs_fine, max_periods, max_abs, start)
        if record:
            # where the search ended, on: a response that never settles
            # (chaos) differs from period to period, as measured; one
            # period more says whether the record is periodic
            y = osc.simulate_fine(np.tile(u_fine, P + 1), fs=fs_fine, periodic=False,
                                  initial_state=steady.final_state, max_abs=max_abs).y
            return y[:-u_fine.size], _repeats(y, P + 1), None, 1
        return steady.y, True, steady.final_state, P
    start = _steady(_frozen(osc), u_fine, fs_fine, max_periods, max_abs, start).final_state
    return osc.simulate_fine(np.tile(u_fine, P), fs=fs_fine, periodic=False,
                             initial_state=_continuation_state(osc, start), max_abs=max_abs).y, False, None, 1


def simulate_signals(osc, signals, transform=None, *, noise_rms=0.0, random_state=None,
                     max_periods=MAX_PERIODS, max_abs=None, record=False, steady_states=None):
    """Simulate ``osc`` on every signal of a :class:`SignalSet`.

    Parameters
    ----------
    osc : Oscillator
    signals : SignalSet
    transform : callable or None
        ``transform(u_fine, fs_fine, periodic)`` applied to the input at the
        integration rate (actuator effects).
    noise_rms : float, default=0.0
        Output noise added at the integration rate before decimation,
        band-limited to the data's Nyquist frequency (the benchmark's noise).
    random_state : int, RandomState instance or None
        Seed of the noise.
    max_periods : int, default=MAX_PERIODS
        Cap on the periods of each steady-state search (fits use
        ``FIT_MAX_PERIODS``).
    max_abs : float, default=None
        Displacement bound at the integration rate: a simulation that
        exceeds it stops there with ``FloatingPointError`` (a fit's trial
        point running away costs one period, not ``max_periods``).
    record : bool, default=False
        Simulate each periodic signal as a laboratory records it (data
        making): its ``P`` periods integrated one after the other from
        where the steady-state search ended.  A settled response gives the
        steady state repeated, as without ``record``; one that does not
        settle (a chaotic response) gives periods that differ, where
        repeating the search's last period would give data that no
        structure produces.
    steady_states : list, default=None
        When a list, filled with each signal's steady state (the
        integrator's state at its period start, None where there is none):
        :func:`simulate_sensitivities` at the same parameters starts there.

    Returns
    -------
    y : list of ndarray (n_samples_i,)
        Displacement at the data rate.  Raises ``FloatingPointError`` when
        the simulation diverges.
    """
    rng = check_random_state(random_state)
    fs_fine = signals.fs * signals.oversampling
    starts = signals.starts or [None] * len(signals.u_fine)

    def decimated(y_fine, circular, repeats):
        if signals.oversampling > 1:
            y_fine = decimate_fir(y_fine, signals.decimation, periodic=circular)
        return np.tile(y_fine, repeats) if repeats > 1 else y_fine

    def one(u_fine, P, start):
        y_fine, circular, steady, repeats = _fine_response(osc, u_fine, P, fs_fine, transform, max_periods,
                                                           max_abs, start, record)
        if noise_rms > 0:
            # noise differs from period to period and comes from one
            # generator in signal order: added to the whole record below
            return np.tile(y_fine, repeats), circular, steady
        return decimated(y_fine, circular, repeats), circular, steady

    out = []
    for y, circular, steady in each_in_threads(one, signals.u_fine, signals.n_periods, starts):
        if steady_states is not None:
            steady_states.append(steady)
        if noise_rms > 0:
            y = decimated(y + band_limited_noise(y.size, fs=fs_fine, f_max=signals.fs / 2, rms=noise_rms,
                                                 random_state=rng), circular, 1)
        out.append(y)
    if signals.correction is not None:
        out = [y + c for y, c in zip(out, signals.correction)]
    return out


def simulate_sensitivities(osc, signals, transform=None, *, max_periods=MAX_PERIODS, max_abs=None,
                           steady_states=None):
    """Each signal's derivatives, at the data rate, by the oscillator's
    physical parameters (:attr:`Oscillator.parameter_vector`), from the
    integrator's own sensitivity recursion (see
    :meth:`Oscillator.sensitivity`): a Jacobian for the price of about two
    simulations, where forward differences cost one per parameter.

    A periodic signal's steady state is searched as in
    :func:`simulate_signals` (or taken from ``steady_states``, those it
    filled at the same parameters), then its period is run once more with
    the sensitivities, decimated by the same filter as the displacement
    (circularly, one period, then repeated); a coarse set's added
    correction is a constant and has none.  Raises ``ValueError`` for what
    the recursion does not cover (a time-varying oscillator's periodic
    signal, a user's force element): the caller differences instead.

    Returns
    -------
    dy : list of ndarray (n_samples_i, n_parameters)
    """
    fs_fine = signals.fs * signals.oversampling
    starts = signals.starts or [None] * len(signals.u_fine)
    known = steady_states or [None] * len(signals.u_fine)

    def one(u_fine, P, start, state):
        periodic = P > 0
        if transform is not None:
            u_fine = transform(u_fine, fs_fine, periodic)
        if periodic:
            if osc.time_varying:
                raise ValueError("a time-varying oscillator has no periodic sensitivity.")
            if state is None:
                state = _steady(osc, u_fine, fs_fine, max_periods, max_abs, start).final_state
            dy = osc.sensitivity(u_fine, fs=fs_fine, periodic=True, steady_state=state)[1]
        else:
            dy = osc.sensitivity(u_fine, fs=fs_fine, periodic=False)[1]
        if signals.oversampling > 1:
            dy = decimate_columns(dy, signals.decimation, periodic=periodic)
        return np.tile(dy, (P, 1)) if periodic else dy

    return each_in_threads(one, signals.u_fine, signals.n_periods, starts, known)
