"""Candidate unmodelled effects: what each adds to the nominal simulator.

An effect is described by a few dimensionless parameters ``theta`` that are
turned into physical values with the scales of the measured data (input force
rms ``F``, displacement rms ``Y``, velocity rms ``V``, duration ``T``), so
that one optimiser setting fits every effect on every structure, and zero
(or the listed start) means "no effect".  An effect changes the nominal
oscillator (extra force elements, other linear parameters) and may transform
the input before it reaches the structure (saturation, delay).
"""
from dataclasses import dataclass, field

import numpy as np

from ...physics.forces import (
    BoucWen,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    CustomForce,
    ForceElement,
    QuadraticDamping,
    QuadraticStiffness,
    StiffnessDrift,
)
from ...physics.oscillator import Oscillator
from .clues import backlash_spring, backlash_start, force_law_start
from .stiffness_start import recalibration_start, second_mode_joint_start, second_mode_start

__all__ = ["Scales", "Effect", "default_effects", "make_effect", "recalibration_effect", "BUILT_IN",
           "NOMINAL_PARAMETERS"]

#: The nominal oscillator's linear parameters a recalibration may refit.
NOMINAL_PARAMETERS = ("mass", "damping", "stiffness")


@dataclass(frozen=True)
class Scales:
    """Scales of the measured data that make effect parameters dimensionless.

    Attributes
    ----------
    force : float
        Rms of the input force, N.
    displacement : float
        Rms of the measured displacement, m.
    velocity : float
        Rms of the measured velocity, m/s.
    duration : float
        Duration of the longest training signal, s.
    u_peak : float
        Largest absolute input value, N.
    fs : float
        Data rate, Hz.
    """

    force: float
    displacement: float
    velocity: float
    duration: float
    u_peak: float
    fs: float

    @property
    def stiffness(self):
        """Force per displacement at the measured levels, N/m."""
        return self.force / self.displacement


@dataclass
class Effect:
    """One candidate effect.

    Attributes
    ----------
    name : str
        Name used in reports.
    param_names : tuple of str
        Names of the physical parameters reported.
    starts : list of ndarray
        Starting points of ``theta`` (the best by training error is refined).
    bounds : (ndarray, ndarray)
        Lower and upper bounds of ``theta``.
    build : callable
        ``build(theta, nominal, scales) -> (forces, linear, input_transform,
        physical)``: extra force elements, a dict of changed linear
        parameters (``mass``, ``damping``, ``stiffness``), an input transform
        ``f(u_fine, fs_fine, periodic)`` or None, and a dict of the physical
        parameter values.
    description : str
        One line saying what the effect is.
    is_recalibration : bool
        Whether the effect only refits the nominal parameters.
    data_start : callable or None
        ``data_start(clues, nominal, scales, bounds) -> theta or None``: a
        start read from the training data before any fit (see
        :mod:`sklearn_pnlss.gap.candidates.clues`).
    joint_start : callable or None
        ``joint_start(clues, nominal, scales, free) -> theta or None``: a
        start of the effect's ``theta`` followed by that of the freed
        nominal parameters ``free``, read from the missing force by least
        squares (stateless force laws: a cubic spring, quadratic damping,
        backlash; see :mod:`sklearn_pnlss.gap.candidates.clues`).
    """

    name: str
    param_names: tuple
    starts: list
    bounds: tuple
    build: callable
    description: str = ""
    is_recalibration: bool = field(default=False)
    data_start: callable = None
    joint_start: callable = None

    def data_starts(self, clues, nominal, scales):
        """Starting points read from the data (empty without clues or a
        data start), inside the bounds; a data start may give several (rows
        of a 2-D array)."""
        if clues is None or self.data_start is None:
            return []
        theta = self.data_start(clues, nominal, scales, self.bounds)
        if theta is None:
            return []
        return [np.clip(t, *self.bounds) for t in np.atleast_2d(theta) if np.all(np.isfinite(t))]

    @property
    def n_params(self):
        return len(self.param_names)


def _box(*pairs):
    lo, hi = zip(*pairs)
    return np.array(lo, float), np.array(hi, float)


def _no_input(forces, physical, linear=None):
    return tuple(forces), dict(linear or {}), None, physical


# -- built-in effects -----------------------------------------------------------
def _hysteresis(theta, nominal, s):
    # Bouc-Wen with nu = 1: only beta*gamma and beta*delta matter, so beta is
    # fixed to 1 / Y, gamma and delta carry the shape, and the products are
    # what is reported (beta alone is an arbitrary choice).
    alpha = theta[0] * s.stiffness
    beta = 1.0 / s.displacement
    el = BoucWen(alpha, beta, theta[1], theta[2], 1.0)
    return _no_input([el], dict(alpha=alpha, beta_gamma=beta * theta[1], beta_delta=beta * theta[2]))


def _cubic(theta, nominal, s):
    k3 = theta[0] * s.force / s.displacement**3
    return _no_input([CubicStiffness(k3)], dict(k3=k3))


def _quadratic(theta, nominal, s):
    k2 = theta[0] * s.force / s.displacement**2
    return _no_input([QuadraticStiffness(k2)], dict(k2=k2))


def _coulomb(theta, nominal, s):
    fc = theta[0] * s.force
    # Smoothed over 1 % of the rms velocity: close to a sign function at the
    # velocities that carry the response, smooth enough for Newton.
    return _no_input([CoulombFriction(fc, 0.01 * s.velocity)], dict(fc=fc))


def _quadratic_damping(theta, nominal, s):
    c2 = theta[0] * s.force / s.velocity**2
    return _no_input([QuadraticDamping(c2)], dict(c2=c2))


def _backlash(theta, nominal, s):
    kb = theta[0] * s.stiffness
    gap = theta[1] * s.displacement
    return _no_input([backlash_spring(kb, gap, s.displacement)], dict(kb=kb, gap=gap))


def _second_mode(theta, nominal, s):
    # Parametrised by the attached mass (relative to the nominal one), the
    # natural frequency of the attached oscillator (relative to the nominal
    # mode) and its damping ratio: well scaled, and any positive values are
    # a physical structure.
    w1 = np.sqrt(max(nominal.stiffness, 1e-12 * s.stiffness) / nominal.mass)
    m2 = theta[0] * nominal.mass
    w2 = theta[1] * w1
    k2 = m2 * w2**2
    c2 = 2 * theta[2] * m2 * w2
    return _no_input([CoupledMass(m2, c2, k2)], dict(m2=m2, c2=c2, k2=k2, f2_hz=w2 / (2 * np.pi)))


def _drift(theta, nominal, s):
    rate = theta[0] * s.stiffness / s.duration
    return _no_input([StiffnessDrift(rate)], dict(rate=rate))


def _saturation(theta, nominal, s):
    level = theta[0] * s.u_peak

    def transform(u_fine, fs_fine, periodic):
        return np.clip(u_fine, -level, level)

    return (), {}, transform, dict(u_max=level)


def _delay(theta, nominal, s):
    tau = theta[0] / s.fs

    def transform(u_fine, fs_fine, periodic):
        return delay_signal(u_fine, tau * fs_fine, periodic)

    return (), {}, transform, dict(delay_s=tau)


_RECALIBRATED = {
    # theta -> the refitted value, each on the scale of the data
    "mass": lambda t, nominal, s: nominal.mass * (1 + t),
    "damping": lambda t, nominal, s: nominal.damping + t * s.force / s.velocity,
    "stiffness": lambda t, nominal, s: nominal.stiffness + t * s.stiffness,
}
_RECALIBRATION_BOUNDS = {"mass": (-0.9, 10.0), "damping": (-5.0, 5.0), "stiffness": (-5.0, 5.0)}


def recalibration_effect(free=NOMINAL_PARAMETERS):
    """The candidate that refits the nominal parameters named in ``free``
    (a subset of :data:`NOMINAL_PARAMETERS`) and adds no physics."""
    free = tuple(name for name in NOMINAL_PARAMETERS if name in free)
    if not free:
        raise ValueError(f"free must name at least one of {NOMINAL_PARAMETERS}.")

    def build(theta, nominal, s):
        linear = {name: _RECALIBRATED[name](t, nominal, s) for name, t in zip(free, theta)}
        return (), linear, None, dict(linear)

    def data_start(clues, nominal, scales, bounds):
        if not clues.change:
            return None
        full = dict(zip(NOMINAL_PARAMETERS, recalibration_start(clues.change, nominal, scales)))
        return np.array([full[name] for name in free])

    return Effect("recalibration", free, [np.zeros(len(free))],
                  _box(*(_RECALIBRATION_BOUNDS[name] for name in free)), build,
                  "nominal " + ", ".join(free) + " refitted, no new physics", True, data_start)


def delay_signal(u, shift, periodic):
    """``u`` delayed by ``shift`` samples (fractional): circularly by the
    DFT when periodic, by linear interpolation from rest otherwise."""
    if shift == 0:
        return u
    n = u.size
    if periodic:
        k = np.fft.rfftfreq(n)
        return np.fft.irfft(np.fft.rfft(u) * np.exp(-2j * np.pi * k * shift), n)
    t = np.arange(n) - shift
    return np.interp(t, np.arange(n), u, left=0.0, right=u[-1])


def _single(lo, hi, starts=(0.0,)):
    return [np.array([v]) for v in starts], _box((lo, hi))


#: The effects that are one stateless force linear in their one parameter:
#: their starts are a least-squares solve on the missing force.
_FORCE_LAW_EFFECTS = ("cubic_stiffness", "quadratic_stiffness", "coulomb_friction", "quadratic_damping")


def _force_law_starts(build):
    """The data start and the joint start of an effect that is one
    stateless force linear in its one parameter.  Its force at ``theta = 1``
    is read from its own builder, so the scaling lives in one place."""
    def force_law(y, v, scales):
        forces = build(np.ones(1), None, scales)[0]
        return Oscillator(1.0, 0.0, 0.0, forces).restoring_force(y, v)

    def data_start(clues, nominal, scales, bounds):
        return force_law_start(clues, force_law, nominal, scales)

    def joint_start(clues, nominal, scales, free):
        return force_law_start(clues, force_law, nominal, scales, free)
    return data_start, joint_start


def _built_in():
    effects = {}

    def add(name, params, starts, bounds, build, description):
        effects[name] = Effect(name, tuple(params), [np.asarray(s, float) for s in starts], bounds, build,
                               description)

    add("hysteresis", ("alpha", "beta_gamma", "beta_delta"),
        [[0.3, 0.5, 0.0], [0.3, 0.5, -0.5], [1.0, 0.5, -0.7]],
        _box((0.0, 10.0), (-5.0, 5.0), (-5.0, 5.0)), _hysteresis,
        "Bouc-Wen hysteretic force (nu = 1)")
    add("cubic_stiffness", ("k3",), *_single(-2.0, 2.0), _cubic, "cubic spring k3 y^3 (odd)")
    add("quadratic_stiffness", ("k2",), *_single(-2.0, 2.0), _quadratic,
        "quadratic spring k2 y^2 (asymmetric, even)")
    add("coulomb_friction", ("fc",), *_single(-2.0, 2.0), _coulomb, "dry friction fc sign(ydot)")
    add("quadratic_damping", ("c2",), *_single(-2.0, 2.0), _quadratic_damping,
        "quadratic damping c2 ydot |ydot|")
    # Backlash: a clearance beyond the response's peaks is a flat direction
    # (the spring never engages), so the starts span clearances up to three
    # rms displacements (a multisine's peaks) at a soft and a stiff spring.
    add("backlash", ("kb", "gap"), [[kb, g] for kb in (0.3, 1.0) for g in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0)],
        _box((-5.0, 50.0), (0.0, 20.0)), _backlash, "dead-zone spring engaged beyond a clearance")
    add("input_saturation", ("u_max",), *_single(0.05, 1.5, (0.95, 0.8, 0.6)), _saturation,
        "actuator force clipped at +-u_max")
    add("input_delay", ("delay_s",), *_single(-20.0, 200.0, (0.0,)), _delay,
        "input delayed by a (fractional) time")
    add("second_mode", ("m2", "c2", "k2"),
        [[0.2, r, 0.02] for r in (0.5, 0.8, 1.25, 2.0, 3.0)],
        _box((1e-3, 5.0), (0.05, 20.0), (1e-3, 1.0)), _second_mode,
        "a second mass coupled by a spring and a damper")
    add("stiffness_drift", ("rate",), *_single(-1.0, 1.0), _drift,
        "stiffness changing linearly over time")
    effects["recalibration"] = recalibration_effect()
    for name in _FORCE_LAW_EFFECTS:
        effects[name].data_start, effects[name].joint_start = _force_law_starts(effects[name].build)
    effects["second_mode"].data_start = (
        lambda clues, nominal, scales, bounds: clues.change and second_mode_start(clues.change, nominal, bounds))
    second_mode_bounds = effects["second_mode"].bounds
    effects["second_mode"].joint_start = (
        lambda clues, nominal, scales, free: clues.change and second_mode_joint_start(
            clues.change, nominal, scales, second_mode_bounds, free))
    effects["backlash"].data_start = lambda clues, nominal, scales, bounds: backlash_start(clues, scales)
    effects["backlash"].joint_start = (
        lambda clues, nominal, scales, free: backlash_start(clues, scales, nominal=nominal, free=free))
    return effects


BUILT_IN = tuple(_built_in())


def default_effects():
    """Names of the built-in candidate effects.

    Returns
    -------
    names : list of str

    Examples
    --------
    >>> from sklearn_pnlss.gap import default_effects
    >>> default_effects()[:3]
    ['hysteresis', 'cubic_stiffness', 'quadratic_stiffness']
    """
    return list(BUILT_IN)


def _element_effect(element):
    """A user's force element as a candidate: every parameter is fitted,
    relative to its given value (or on a unit scale when it is zero)."""
    p0 = np.asarray(element.parameters(), dtype=float)
    scale = np.where(p0 != 0, np.abs(p0), 1.0)
    names = tuple(element.param_names)
    if isinstance(element, CustomForce):
        name = element.name

        def rebuild(p):
            return element.with_params(p)
    else:
        # a built-in element's parameters are its constructor's arguments
        name = type(element).__name__

        def rebuild(p):
            return type(element)(*p)

    def build(theta, nominal, s):
        p = p0 + theta * scale
        return _no_input([rebuild(p)], dict(zip(names, p)))

    n = p0.size
    return Effect(name, names, [np.zeros(n)], (np.full(n, -50.0), np.full(n, 50.0)), build,
                  f"user element {element!r}")


def make_effect(effect):
    """An :class:`Effect` from a built-in name, a force element or an Effect."""
    if isinstance(effect, Effect):
        return effect
    if isinstance(effect, str):
        table = _built_in()
        if effect not in table:
            raise ValueError(
                f"unknown effect {effect!r}; the built-in effects are {list(table)} "
                "(or pass a ForceElement instance as your own candidate)."
            )
        return table[effect]
    if isinstance(effect, ForceElement):
        return _element_effect(effect)
    raise TypeError(
        f"effects must hold effect names (see default_effects()) or ForceElement "
        f"instances, got {effect!r}."
    )
