"""A linear oscillator read off measured data: the nominal an engineer
builds from the best linear approximation (mass, damping and stiffness from
the resonance, its width and the static gain)."""
import numpy as np

from ..physics.oscillator import Oscillator
from ..utils.validation import as_signal_list, check_period
from .readings import measured_frf

__all__ = ["linear_nominal"]

#: Longest channel delay looked for when the FRF is no oscillator's, samples.
MAX_DELAY_SAMPLES = 10
#: Rms relative FRF error under which an oscillator read through a delay is taken.
DELAYED_FIT_TOL = 0.1


def linear_nominal(X, y, *, fs, period=None, f_band=None):
    """The linear oscillator ``m ydd + c yd + k y = u`` closest to the
    measured frequency response.

    The FRF is the best linear approximation of the data (period-averaged
    H1 of steady-state periodic signals, else Welch's H1); ``m``, ``c`` and
    ``k`` minimise the relative FRF error, a linear least-squares problem
    in the dynamic stiffness ``k - m w^2 + i c w``.  On a nonlinear
    structure this is the nominal an engineer reads off a test: it carries
    the average effect of the nonlinearity at the test level (a hardening
    spring raises ``k``), which is why :class:`GapDiagnosis` refits it with
    every candidate.  When no oscillator fits without it, a delay between
    the channels (up to ``MAX_DELAY_SAMPLES``) is fitted too: a sensor's
    delay turns the phase faster than any oscillator's.

    Parameters
    ----------
    X, y : signals as in :meth:`GapDiagnosis.fit`
        Measured force and displacement.
    fs : float
        Sampling rate, Hz.
    period : int, default=None
        Samples per period when every signal is a whole number of
        steady-state periods.
    f_band : (float, float), default=None
        Band of the fit, Hz; None: every line the input excites.

    Returns
    -------
    Oscillator

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.gap.linear_nominal import linear_nominal
    >>> from sklearn_pnlss.physics import Oscillator
    >>> from sklearn_pnlss.signals import multisine
    >>> X, _ = multisine(1024, fs=750.0, rms=10.0, n_periods=2, random_state=0)
    >>> y = Oscillator(2.0, 10.0, 5e4).simulate(X[0, :, 0], fs=750.0, periodic=True)
    >>> osc = linear_nominal(X, y[None, :, None], fs=750.0, period=1024)
    >>> [round(float(v), 2) for v in (osc.mass, osc.damping, osc.stiffness / 1e4)]
    [2.0, 10.0, 5.0]
    """
    period = check_period(period)
    u_list = [s[:, 0] for s in as_signal_list(X, name="X", min_samples=16)[0]]
    y_list = [s[:, 0] for s in as_signal_list(y, name="y", min_samples=16)[0]]
    if len(u_list) != len(y_list) or any(u.size != v.size for u, v in zip(u_list, y_list)):
        raise ValueError("X and y must hold the same number of signals of the same lengths.")
    lines, G, n = measured_frf(u_list, [y[:, None] for y in y_list], period)
    G = G[:, 0]
    w = 2 * np.pi * lines * fs / n
    if f_band is not None:
        keep = (w >= 2 * np.pi * f_band[0]) & (w <= 2 * np.pi * f_band[1])
        w, G = w[keep], G[keep]
    if w.size < 3:
        raise ValueError("fewer than 3 excited lines in f_band: widen f_band or excite the band.")
    (k, m, c), _ = _oscillator_fit(w, G, 0.0)
    if min(k, m, c) <= 0:
        # A delay between the channels (a sensor, an anti-alias filter)
        # turns the phase faster than any oscillator's: read the oscillator
        # with the delay that fits best (the diagnosis finds the delay
        # itself as the channels' ``input_delay``).
        fits = [_oscillator_fit(w, G, tau) for tau in np.linspace(0.0, MAX_DELAY_SAMPLES / fs, 201)[1:]]
        # an oscillator that fits (10 % rms relative FRF error at most), not
        # one a delay merely makes positive (a sign error of a channel)
        damped = [f for f in fits if min(f[0]) > 0 and f[1] < DELAYED_FIT_TOL**2 * w.size]
        if not damped:
            raise ValueError(f"the measured FRF is not that of a damped oscillator (m = {m:.3g}, c = {c:.3g}, "
                             f"k = {k:.3g}), even with a channel delay of up to {MAX_DELAY_SAMPLES} samples: "
                             "check the channels, or give the band of the first mode as f_band.")
        k, m, c = min(damped, key=lambda f: f[1])[0]
    return Oscillator(float(m), float(c), float(k))


def _oscillator_fit(w, G, delay):
    """``(k, m, c)`` with ``(k - m w^2 + i c w) G e^{i w delay} = 1`` in
    the least-squares sense (relative FRF error), and its residual."""
    Gd = G * np.exp(1j * w * delay)
    A = np.stack([Gd, -w**2 * Gd, 1j * w * Gd], axis=1)
    A, b = np.vstack([A.real, A.imag]), np.concatenate([np.ones(w.size), np.zeros(w.size)])
    theta = np.linalg.lstsq(A, b, rcond=None)[0]
    return theta, float(np.sum((A @ theta - b) ** 2))
