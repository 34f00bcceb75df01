"""Newmark's frequency warping, compensated for a structure simulated at a
low integration rate.

Newmark's average-acceleration rule is the trapezoidal rule: in the steady
state its response at the frequency ``w`` is the continuous structure's at
``W = (2 / h) tan(w h / 2)``, so that every mode rings low, by about
``(w h)^2 / 12``, and its peak is too high and too narrow.  At five steps per
sample of a 200 Hz record a mode at 60 Hz is 1 % low: a third of its
half-power bandwidth at 4 % damping, a 15 % error of the simulated response
where a fit needs the noise's 1 % (measured on a three-mass chain).  Steps
four times shorter cost four times the time.

:func:`prewarped` moves each mode of the linear part instead, as a
bilinear filter is prewarped: its frequency to ``(2 / h) tan(w h / 2)``, its
modal damping and its shape's scale so that the trapezoidal peak's width and
height are the continuous one's.  The connections' forces act through the
same prewarped modes, so their response is corrected as the input's is;
only the shift of a mode by a nonlinear element's own stiffness is left
warped (second order).  The integrator's velocity and acceleration are the
trapezoidal rule's too (``j W`` and ``-W^2`` times the displacement):
:func:`rate_correction` is the factor, per line, that makes them the
continuous ones.
"""
import numpy as np
from scipy.linalg import eigh

from .structure import SENSOR_KINDS

__all__ = ["prewarped", "rate_correction"]

#: Modes are prewarped up to this half step angle ``w h / 2`` (a quarter of
#: the integration rate's Nyquist frequency), held there above it: such a
#: mode is far above any band the integrator should serve, and ``tan``
#: would run away at ``pi / 2``.
MAX_HALF_ANGLE = np.pi / 4


def prewarped(structure, fs):
    """The structure whose trapezoidal response at the rate ``fs`` matches
    the continuous one at each mode's resonance.

    Parameters
    ----------
    structure : Structure
    fs : float
        Integration rate, Hz.

    Returns
    -------
    Structure
        The same points, connections and point matrix; mass, damping and
        stiffness changed in the undamped modes' coordinates.

    Examples
    --------
    A mode at 60 Hz integrated at 1 kHz rings at 59.3 Hz; prewarped, at
    60.0 Hz:

    >>> import numpy as np
    >>> from sklearn_pnlss.physics import Structure
    >>> from sklearn_pnlss.physics.prewarp import prewarped
    >>> s = Structure([[1.0]], [[0.0]], [[(2 * np.pi * 60) ** 2]])
    >>> warped = prewarped(s, 1000.0)
    >>> w = np.sqrt(warped.stiffness[0, 0] / warped.mass[0, 0])
    >>> round(float(2 * 1000.0 * np.arctan(w / 2000.0) / (2 * np.pi)), 3)
    60.0
    """
    h = 1.0 / float(fs)
    w2, shapes = eigh(structure.stiffness, structure.mass)  # mass-normalised
    x = np.minimum(np.sqrt(np.clip(w2, 0.0, None)) * h / 2, MAX_HALF_ANGLE)
    safe = np.where(x > 0, x, 1.0)
    raised = np.where(x > 0, np.tan(safe) / safe, 1.0)  # W / w at the mode
    slope = 1.0 / np.cos(x) ** 2  # dW / dw at the mode
    # near its resonance a mode adds phi phi^T / (2 w_n (w_n - w + j c / 2)),
    # c its damping coefficient; integrated, it runs on W(w), which moves
    # ``slope`` times faster: the damping times ``slope`` keeps the peak's
    # width, the shapes times sqrt(raised * slope) its height
    scale = np.sqrt(raised * slope)
    # the new matrices are P^T diag(...) P with P = diag(1/s) phi^T M, the
    # inverse of the rescaled shapes phi diag(s)
    to_modes = structure.mass @ shapes / scale
    modal_damping = shapes.T @ structure.damping @ shapes
    root = np.sqrt(slope)
    out = structure.with_connections()
    out.mass = to_modes @ to_modes.T
    out.stiffness = (to_modes * (w2 * raised**2)) @ to_modes.T
    out.damping = to_modes @ (root[:, None] * modal_damping * root[None, :]) @ to_modes.T
    return out


def rate_correction(freqs, fs, sensors):
    """Per line, the factor that turns the trapezoidal rule's velocity and
    acceleration at the rate ``fs`` into the continuous ones.

    Parameters
    ----------
    freqs : array-like of shape (n_freqs,)
        Hz, below ``fs / 2``.
    fs : float
        Integration rate, Hz.
    sensors : sequence of (str, str)
        ``(point, kind)`` of each output.

    Returns
    -------
    ndarray of shape (n_freqs, n_sensors)
        ``(x / tan x) ** k`` with ``x = pi f / fs`` and ``k`` the kind's
        order of derivative (1 for a displacement).
    """
    x = np.pi * np.asarray(freqs, dtype=np.float64) / float(fs)
    safe = np.where(x > 0, x, 1.0)
    ratio = np.where(x > 0, safe / np.tan(safe), 1.0)
    powers = np.array([SENSOR_KINDS.index(kind) for _, kind in sensors])
    return ratio[:, None] ** powers[None, :]
