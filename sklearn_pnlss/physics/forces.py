"""Force elements of a single-degree-of-freedom oscillator.

A force element adds a restoring force ``F(y, ydot, z)`` to the equation of
motion and may carry internal states ``z`` with ``zdot = g(y, ydot, z)``.
The Python classes below only describe an element (kind code, flat parameter
vector, number of internal states); the numerical work is done by compiled
functions in :mod:`sklearn_pnlss.physics._newmark`, which dispatch on the
kind code.

Adding an element type takes three small steps: a kind code constant, a pair
of numba functions (force and state rate, with their partial derivatives) in
``_newmark.py`` plus one ``elif`` in each dispatcher, and a class here.
"""
from numbers import Real

import numpy as np

# Kind codes understood by the compiled kernel; keep in sync with _newmark.py.
KIND_BOUC_WEN = 1
KIND_CUBIC_STIFFNESS = 2

__all__ = ["ForceElement", "BoucWen", "CubicStiffness"]


def _check_finite_real(name, value):
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {value!r}.")
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}.")
    return value


class ForceElement:
    """Base class of the force elements.

    Subclasses define ``kind`` (an integer code known to the compiled kernel),
    ``n_states`` (number of internal states) and :meth:`parameters` (the flat
    float parameter vector in the order the kernel reads it).
    """

    kind = 0
    n_states = 0

    def parameters(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        names = self._param_names
        args = ", ".join(f"{n}={getattr(self, n)!r}" for n in names)
        return f"{type(self).__name__}({args})"

    def __eq__(self, other):
        return type(self) is type(other) and np.array_equal(
            self.parameters(), other.parameters()
        )

    def __hash__(self):
        return hash((type(self).__name__, tuple(self.parameters())))


class BoucWen(ForceElement):
    r"""Bouc-Wen hysteretic force.

    The element adds the force :math:`F = z` to the equation of motion, where
    the internal state obeys

    .. math:: \dot z = \alpha \dot y - \beta\,(\gamma |\dot y| |z|^{\nu-1} z
              + \delta \dot y |z|^\nu).

    Parameters
    ----------
    alpha : float, default=5e4
        Linear stiffness of the hysteretic branch, N/m.
    beta : float, default=1e3
        Scale of the hysteretic shape terms, 1/m.
    gamma : float, default=0.8
        Weight of the :math:`|\dot y|` term.
    delta : float, default=-1.1
        Weight of the :math:`\dot y` term.
    nu : float, default=1.0
        Exponent of the shape terms; must be >= 1 so that the Jacobian stays
        finite at ``z = 0``.

    Examples
    --------
    >>> from sklearn_pnlss.physics import BoucWen
    >>> BoucWen().n_states
    1
    """

    kind = KIND_BOUC_WEN
    n_states = 1
    _param_names = ("alpha", "beta", "gamma", "delta", "nu")

    def __init__(self, alpha=5e4, beta=1e3, gamma=0.8, delta=-1.1, nu=1.0):
        self.alpha = _check_finite_real("alpha", alpha)
        self.beta = _check_finite_real("beta", beta)
        self.gamma = _check_finite_real("gamma", gamma)
        self.delta = _check_finite_real("delta", delta)
        self.nu = _check_finite_real("nu", nu)
        if self.nu < 1.0:
            raise ValueError(f"nu must be >= 1, got {nu!r}.")

    def parameters(self):
        return np.array([self.alpha, self.beta, self.gamma, self.delta, self.nu])


class CubicStiffness(ForceElement):
    r"""Cubic spring, :math:`F = k_3 y^3`, without internal states.

    Parameters
    ----------
    k3 : float
        Cubic stiffness coefficient, N/m^3.

    Examples
    --------
    >>> from sklearn_pnlss.physics import CubicStiffness
    >>> CubicStiffness(1e9).n_states
    0
    """

    kind = KIND_CUBIC_STIFFNESS
    n_states = 0
    _param_names = ("k3",)

    def __init__(self, k3):
        self.k3 = _check_finite_real("k3", k3)

    def parameters(self):
        return np.array([self.k3])


def pack_forces(forces):
    """Flatten a sequence of force elements into the kernel's arrays.

    Returns
    -------
    kinds : ndarray of int64, shape (n_elements,)
    p_offsets : ndarray of int64, shape (n_elements + 1,)
        Element ``e`` reads ``params[p_offsets[e]:p_offsets[e + 1]]``.
    params : ndarray of float64
    z_offsets : ndarray of int64, shape (n_elements + 1,)
        Element ``e`` owns internal states ``z[z_offsets[e]:z_offsets[e + 1]]``.
    """
    forces = tuple(forces)
    for i, f in enumerate(forces):
        if not isinstance(f, ForceElement):
            raise TypeError(
                f"forces[{i}] must be a ForceElement (e.g. BoucWen()), got {f!r}."
            )
    kinds = np.array([f.kind for f in forces], dtype=np.int64)
    plist = [np.asarray(f.parameters(), dtype=np.float64) for f in forces]
    p_offsets = np.zeros(len(forces) + 1, dtype=np.int64)
    z_offsets = np.zeros(len(forces) + 1, dtype=np.int64)
    for e, f in enumerate(forces):
        p_offsets[e + 1] = p_offsets[e] + plist[e].size
        z_offsets[e + 1] = z_offsets[e] + f.n_states
    params = np.concatenate(plist) if plist else np.zeros(0)
    return kinds, p_offsets, params, z_offsets
