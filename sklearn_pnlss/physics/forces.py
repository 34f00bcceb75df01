"""Force elements of a single-degree-of-freedom oscillator.

A force element adds a restoring force ``F(y, ydot, z)`` to the equation of
motion and may carry internal states ``z`` with ``zdot = g(y, ydot, z)``.
The Python classes below only describe an element (kind code, flat parameter
vector, number of internal states); the numerical work is done by compiled
functions in :mod:`sklearn_pnlss.physics._newmark`, which dispatch on the
kind code.

Adding an element type to the library takes three small steps: a kind code
constant, a pair of numba functions (force and state rate, with their partial
derivatives) in ``_newmark.py`` plus one ``elif`` in each dispatcher, and a
class here.  Users add their own stateless element without touching the
kernels through :class:`CustomForce` (a compiled function of ``y, ydot``).
"""
from numbers import Real

import numpy as np

# Kind codes understood by the compiled kernel; keep in sync with _newmark.py.
KIND_BOUC_WEN = 1
KIND_CUBIC_STIFFNESS = 2
KIND_QUADRATIC_STIFFNESS = 3
KIND_COULOMB_FRICTION = 4
KIND_QUADRATIC_DAMPING = 5
KIND_DEAD_ZONE_SPRING = 6
KIND_COUPLED_MASS = 7
KIND_STIFFNESS_DRIFT = 8
KIND_CUSTOM = 9
KIND_SERIES_DAMPER = 10

__all__ = [
    "ForceElement",
    "BoucWen",
    "CubicStiffness",
    "QuadraticStiffness",
    "CoulombFriction",
    "QuadraticDamping",
    "DeadZoneSpring",
    "CoupledMass",
    "StiffnessDrift",
    "SeriesDamper",
    "CustomForce",
]


def _check_finite_real(name, value):
    if isinstance(value, bool) or not isinstance(value, Real):
        raise TypeError(f"{name} must be a real number, got {value!r}.")
    value = float(value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}.")
    return value


def _check_positive(name, value):
    value = _check_finite_real(name, value)
    if value <= 0:
        raise ValueError(f"{name} must be > 0, got {value!r}.")
    return value


class ForceElement:
    """Base class of the force elements.

    Subclasses define ``kind`` (an integer code known to the compiled kernel),
    ``n_states`` (number of internal states), :meth:`parameters` (the flat
    float parameter vector in the order the kernel reads it) and
    ``param_names``.

    Attributes
    ----------
    param_names : tuple of str
        Names of the entries of :meth:`parameters`, in order.  For the
        built-in elements they are also the constructor's arguments, so
        ``type(element)(*element.parameters())`` rebuilds the element;
        a :class:`CustomForce` names its vector ``p0, p1, ...``.
    """

    kind = 0
    n_states = 0
    param_names = ()
    #: True when the force depends on time itself (no periodic steady state).
    time_varying = False

    def parameters(self):  # pragma: no cover - abstract
        raise NotImplementedError

    def __repr__(self):
        args = ", ".join(f"{n}={getattr(self, n)!r}" for n in self.param_names)
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
    param_names = ("alpha", "beta", "gamma", "delta", "nu")

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
    param_names = ("k3",)

    def __init__(self, k3):
        self.k3 = _check_finite_real("k3", k3)

    def parameters(self):
        return np.array([self.k3])


class QuadraticStiffness(ForceElement):
    r"""Quadratic spring, :math:`F = k_2 y^2`: an asymmetric (even) stiffness.

    A spring stiffer in one direction than the other; it creates even
    harmonics and a static offset under a zero-mean input.

    Parameters
    ----------
    k2 : float
        Quadratic stiffness coefficient, N/m^2.

    Examples
    --------
    >>> from sklearn_pnlss.physics import QuadraticStiffness
    >>> QuadraticStiffness(1e7).parameters()
    array([10000000.])
    """

    kind = KIND_QUADRATIC_STIFFNESS
    param_names = ("k2",)

    def __init__(self, k2):
        self.k2 = _check_finite_real("k2", k2)

    def parameters(self):
        return np.array([self.k2])


class CoulombFriction(ForceElement):
    r"""Dry friction, :math:`F = F_c \tanh(\dot y / v_s)`.

    The sign function of Coulomb friction is smoothed over a velocity
    ``v_s`` so that the implicit integrator keeps a continuous Jacobian; with
    ``v_s`` well below the velocities of interest the force is the Coulomb
    force :math:`F_c\,\mathrm{sign}(\dot y)`.

    Parameters
    ----------
    fc : float
        Friction force level, N.
    v_smooth : float, default=1e-3
        Smoothing velocity ``v_s``, m/s (> 0).

    Examples
    --------
    >>> from sklearn_pnlss.physics import CoulombFriction
    >>> CoulombFriction(2.0)
    CoulombFriction(fc=2.0, v_smooth=0.001)
    """

    kind = KIND_COULOMB_FRICTION
    param_names = ("fc", "v_smooth")

    def __init__(self, fc, v_smooth=1e-3):
        self.fc = _check_finite_real("fc", fc)
        self.v_smooth = _check_positive("v_smooth", v_smooth)

    def parameters(self):
        return np.array([self.fc, self.v_smooth])


class QuadraticDamping(ForceElement):
    r"""Quadratic (aerodynamic or turbulent) damping, :math:`F = c_2 \dot y |\dot y|`.

    Parameters
    ----------
    c2 : float
        Quadratic damping coefficient, N s^2/m^2.

    Examples
    --------
    >>> from sklearn_pnlss.physics import QuadraticDamping
    >>> QuadraticDamping(50.0).n_states
    0
    """

    kind = KIND_QUADRATIC_DAMPING
    param_names = ("c2",)

    def __init__(self, c2):
        self.c2 = _check_finite_real("c2", c2)

    def parameters(self):
        return np.array([self.c2])


class DeadZoneSpring(ForceElement):
    r"""Spring engaged only beyond a clearance (backlash, impact stops).

    .. math:: F = k_b\,[\sigma(y - g) - \sigma(-y - g)],
              \qquad \sigma(x) = s \log(1 + e^{x/s})

    For ``s -> 0`` this is the dead-zone spring ``k_b (y - g sign(y))`` for
    ``|y| > g`` and zero inside the clearance; the softplus ``sigma`` rounds
    the corners over a width ``s`` so that Newton's method stays smooth.

    Parameters
    ----------
    kb : float
        Stiffness of the engaged spring, N/m.
    gap : float
        Clearance ``g`` on each side, m (>= 0).
    smoothing : float, default=None
        Corner width ``s``, m (> 0); None takes ``gap / 20`` (or 1e-9 m for a
        zero gap).

    Examples
    --------
    >>> from sklearn_pnlss.physics import DeadZoneSpring
    >>> DeadZoneSpring(5e4, 2e-4).smoothing
    1e-05
    """

    kind = KIND_DEAD_ZONE_SPRING
    param_names = ("kb", "gap", "smoothing")

    def __init__(self, kb, gap, smoothing=None):
        self.kb = _check_finite_real("kb", kb)
        self.gap = _check_finite_real("gap", gap)
        if self.gap < 0:
            raise ValueError(f"gap must be >= 0, got {gap!r}.")
        if smoothing is None:
            smoothing = self.gap / 20 if self.gap > 0 else 1e-9
        self.smoothing = _check_positive("smoothing", smoothing)

    def parameters(self):
        return np.array([self.kb, self.gap, self.smoothing])


class CoupledMass(ForceElement):
    r"""A second mass attached by a spring and a damper: a second mode.

    .. math:: F = k_2 (y - y_2) + c_2 (\dot y - \dot y_2), \qquad
              m_2 \ddot y_2 = k_2 (y - y_2) + c_2 (\dot y - \dot y_2)

    The internal states are ``y_2`` and its velocity.

    Parameters
    ----------
    m2 : float
        Attached mass, kg (> 0).
    c2 : float
        Damping of the link, N s/m (>= 0).
    k2 : float
        Stiffness of the link, N/m (>= 0).

    Examples
    --------
    >>> from sklearn_pnlss.physics import CoupledMass
    >>> CoupledMass(0.2, 2.0, 3e4).n_states
    2
    """

    kind = KIND_COUPLED_MASS
    n_states = 2
    param_names = ("m2", "c2", "k2")

    def __init__(self, m2, c2, k2):
        self.m2 = _check_positive("m2", m2)
        self.c2 = _check_finite_real("c2", c2)
        self.k2 = _check_finite_real("k2", k2)
        if self.c2 < 0 or self.k2 < 0:
            raise ValueError(f"c2 and k2 must be >= 0, got c2={c2!r}, k2={k2!r}.")

    def parameters(self):
        return np.array([self.m2, self.c2, self.k2])


class StiffnessDrift(ForceElement):
    r"""Stiffness changing linearly with time, :math:`F = \rho\, t\, y`.

    Models slow changes over an experiment (temperature, wear, loosening):
    the stiffness is ``k + rho t`` at time ``t`` since the start of the
    simulation.  The element carries the clock ``t`` as its internal state,
    so a simulation with it has no periodic steady state: simulate from a
    known state (``periodic=False``).

    Parameters
    ----------
    rate : float
        Stiffness change per second, N/(m s).

    Examples
    --------
    >>> from sklearn_pnlss.physics import StiffnessDrift
    >>> StiffnessDrift(-20.0).time_varying
    True
    """

    kind = KIND_STIFFNESS_DRIFT
    n_states = 1
    time_varying = True
    param_names = ("rate",)

    def __init__(self, rate):
        self.rate = _check_finite_real("rate", rate)

    def parameters(self):
        return np.array([self.rate])


class SeriesDamper(ForceElement):
    r"""A spring and a damper in series between the mass and the ground (a
    Maxwell element: a viscoelastic mount, a rubber isolator).

    .. math:: F = k_s (y - w), \qquad c_s \dot w = k_s (y - w)

    The internal state is ``w``, the displacement of the massless node
    between the spring and the damper.  Slow motion relaxes through the
    damper (no static stiffness); fast motion meets the spring: the
    element stiffens and damps most near its relaxation frequency
    :math:`k_s / (2 \pi c_s)`.

    Parameters
    ----------
    cs : float
        Damping of the damper, N s/m (> 0).
    ks : float
        Stiffness of the spring, N/m (>= 0).

    Examples
    --------
    >>> from sklearn_pnlss.physics import SeriesDamper
    >>> SeriesDamper(200.0, 1e4).n_states
    1
    """

    kind = KIND_SERIES_DAMPER
    n_states = 1
    param_names = ("cs", "ks")

    def __init__(self, cs, ks):
        self.cs = _check_positive("cs", cs)
        self.ks = _check_finite_real("ks", ks)
        if self.ks < 0:
            raise ValueError(f"ks must be >= 0, got {ks!r}.")

    def parameters(self):
        return np.array([self.cs, self.ks])


class CustomForce(ForceElement):
    r"""A user's own stateless force element, :math:`F = f(p, y, \dot y)`.

    Parameters
    ----------
    function : numba-compiled function
        ``function(p, y, yd) -> (F, dF/dy, dF/dyd)`` where ``p`` is the
        parameter vector (1-D float64 array) and ``y``, ``yd`` the
        displacement and velocity; compile it with ``numba.njit``.  The
        partial derivatives must be exact: the implicit integrator's Newton
        iterations use them.
    params : array-like of float, default=()
        The parameter vector ``p``.
    name : str, default="custom"
        Name shown in reports.

    Notes
    -----
    The first simulation with a new ``function`` compiles that function and
    a small dispatch around it, once per function object and process; the
    integrator itself comes from numba's disk cache, compiled once for every
    user's element (``tests/test_simulator.py`` checks that a new process
    with a new function loads it from there). Define the function once, at
    module level, and reuse it (``with_params`` keeps it).

    Examples
    --------
    >>> import numpy as np
    >>> from numba import njit
    >>> from sklearn_pnlss.physics import CustomForce, Oscillator
    >>> @njit
    ... def softening(p, y, yd):
    ...     return -p[0] * y**3, -3 * p[0] * y**2, 0.0
    >>> osc = Oscillator(2.0, 10.0, 5e4, forces=(CustomForce(softening, [1e9]),))
    >>> u = 10 * np.sin(2 * np.pi * 30 * np.arange(750) / 750)
    >>> osc.simulate(u, fs=750.0, periodic=True).shape
    (750,)
    """

    kind = KIND_CUSTOM

    def __init__(self, function, params=(), name="custom"):
        if not hasattr(function, "py_func"):
            raise TypeError(
                "function must be compiled with numba.njit, e.g. "
                "@njit def f(p, y, yd): return F, dF_dy, dF_dyd; "
                f"got {function!r}."
            )
        self.function = function
        self.params = np.array(params, dtype=np.float64).ravel()
        if not np.all(np.isfinite(self.params)):
            raise ValueError("params must be finite.")
        self.name = str(name)

    def __repr__(self):
        return (f"CustomForce({getattr(self.function, '__name__', 'function')}, "
                f"params={self.params.tolist()!r}, name={self.name!r})")

    def __eq__(self, other):
        return (type(self) is type(other) and self.function is other.function
                and np.array_equal(self.params, other.params))

    def __hash__(self):
        return hash((id(self.function), tuple(self.params)))

    @property
    def param_names(self):
        """Names of the parameter vector's entries: ``("p0", "p1", ...)``."""
        return tuple(f"p{i}" for i in range(self.params.size))

    def with_params(self, params):
        """A copy with another parameter vector (same function and name)."""
        return CustomForce(self.function, params, self.name)

    def parameters(self):
        return self.params


def pack_forces(forces):
    """Flatten a sequence of force elements into the kernel's arrays.

    Returns
    -------
    kinds : ndarray of int64, shape (n_elements,)
    p_offsets : ndarray of int64, shape (n_elements + 1,)
        Element ``e`` reads ``params[p_offsets[e]:p_offsets[e + 1]]``.
    params : ndarray of float64
        For a :class:`CustomForce`, the first entry of its slice is its index
        among the custom elements, the user's parameters follow.
    z_offsets : ndarray of int64, shape (n_elements + 1,)
        Element ``e`` owns internal states ``z[z_offsets[e]:z_offsets[e + 1]]``.
    custom_functions : tuple
        The compiled functions of the custom elements, in order.
    """
    forces = tuple(forces)
    for i, f in enumerate(forces):
        if not isinstance(f, ForceElement):
            raise TypeError(
                f"forces[{i}] must be a ForceElement (e.g. BoucWen()), got {f!r}."
            )
    kinds = np.array([f.kind for f in forces], dtype=np.int64)
    plist, custom = [], []
    for f in forces:
        p = np.asarray(f.parameters(), dtype=np.float64)
        if f.kind == KIND_CUSTOM:
            p = np.concatenate([[len(custom)], p])
            custom.append(f.function)
        plist.append(p)
    p_offsets = np.zeros(len(forces) + 1, dtype=np.int64)
    z_offsets = np.zeros(len(forces) + 1, dtype=np.int64)
    for e, f in enumerate(forces):
        p_offsets[e + 1] = p_offsets[e] + plist[e].size
        z_offsets[e + 1] = z_offsets[e] + f.n_states
    params = np.concatenate(plist) if plist else np.zeros(0)
    return kinds, p_offsets, params, z_offsets, tuple(custom)
