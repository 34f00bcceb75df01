"""The built-in candidate effects, one class each, and the candidates a
diagnosis is given by name or force element (see
:class:`~sklearn_pnlss.gap.candidates.effect.Effect` for what an effect is).
"""
import numpy as np

from ...physics.forces import (
    BoucWen,
    CoulombFriction,
    CoupledMass,
    CubicStiffness,
    CustomForce,
    DeadZoneSpring,
    ForceElement,
    QuadraticDamping,
    QuadraticStiffness,
    SeriesDamper,
    StiffnessDrift,
)
from ...physics.oscillator import Oscillator
from .clues import backlash_start, force_law_start
from .effect import NOMINAL_PARAMETERS, Effect, EffectTerms, Scales, recalibration_unit
from .stiffness_start import recalibration_start, second_mode_joint_start, second_mode_start

__all__ = ["Scales", "Effect", "default_effects", "make_effect", "BUILT_IN", "NOMINAL_PARAMETERS", "Recalibration",
           "Hysteresis", "CubicSpring", "QuadraticSpring", "DryFriction", "QuadraticDamper", "Backlash",
           "InputSaturation", "InputDelay", "SecondMode", "ViscoelasticMount", "StiffnessDriftEffect", "ElementEffect",
           "delay_signal"]


class Hysteresis(Effect):
    # Bouc-Wen with nu = 1: only beta*gamma and beta*delta matter, so beta is
    # fixed to 1 / Y, gamma and delta carry the shape, and the products are
    # what is reported (beta alone is an arbitrary choice).
    name = "hysteresis"
    description = "Bouc-Wen hysteretic force (nu = 1)"
    param_names = ("alpha", "beta_gamma", "beta_delta")
    limits = ((0.0, 10.0), (-5.0, 5.0), (-5.0, 5.0))
    listed_starts = ((0.3, 0.5, 0.0), (0.3, 0.5, -0.5), (1.0, 0.5, -0.7))

    def build(self, theta, nominal, s):
        alpha = theta[0] * s.stiffness
        beta = 1.0 / s.displacement
        return EffectTerms((BoucWen(alpha, beta, theta[1], theta[2], 1.0),),
                           physical=dict(alpha=alpha, beta_gamma=beta * theta[1], beta_delta=beta * theta[2]))


class _ForceLaw(Effect):
    """One stateless force linear in its one parameter: its starts are a
    least-squares solve on the missing force, read with its own force at
    ``theta = 1`` (so the scaling lives in :meth:`build` alone)."""

    limits = ((-2.0, 2.0),)
    listed_starts = ((0.0,),)

    def _force_law(self, y, v, scales):
        return Oscillator(1.0, 0.0, 0.0, self.build(np.ones(1), None, scales).forces).restoring_force(y, v)

    def data_start(self, clues, nominal, scales):
        return force_law_start(clues, self._force_law, nominal, scales)

    def joint_start(self, clues, nominal, scales, free):
        return force_law_start(clues, self._force_law, nominal, scales, free)


class CubicSpring(_ForceLaw):
    name = "cubic_stiffness"
    description = "cubic spring k3 y^3 (odd)"
    param_names = ("k3",)

    def build(self, theta, nominal, s):
        k3 = theta[0] * s.force / s.displacement**3
        return EffectTerms((CubicStiffness(k3),), physical=dict(k3=k3))


class QuadraticSpring(_ForceLaw):
    name = "quadratic_stiffness"
    description = "quadratic spring k2 y^2 (asymmetric, even)"
    param_names = ("k2",)

    def build(self, theta, nominal, s):
        k2 = theta[0] * s.force / s.displacement**2
        return EffectTerms((QuadraticStiffness(k2),), physical=dict(k2=k2))


class DryFriction(_ForceLaw):
    name = "coulomb_friction"
    description = "dry friction fc sign(ydot)"
    param_names = ("fc",)

    def build(self, theta, nominal, s):
        fc = theta[0] * s.force
        # Smoothed over 1 % of the rms velocity: close to a sign function at
        # the velocities that carry the response, smooth enough for Newton.
        return EffectTerms((CoulombFriction(fc, 0.01 * s.velocity),), physical=dict(fc=fc))


class QuadraticDamper(_ForceLaw):
    name = "quadratic_damping"
    description = "quadratic damping c2 ydot |ydot|"
    param_names = ("c2",)

    def build(self, theta, nominal, s):
        c2 = theta[0] * s.force / s.velocity**2
        return EffectTerms((QuadraticDamping(c2),), physical=dict(c2=c2))


class Backlash(Effect):
    # A clearance beyond the response's peaks is a flat direction (the
    # spring never engages), so the starts span clearances up to three rms
    # displacements (a multisine's peaks) at a soft and a stiff spring.
    name = "backlash"
    description = "dead-zone spring engaged beyond a clearance"
    param_names = ("kb", "gap")
    limits = ((-5.0, 50.0), (0.0, 20.0))
    listed_starts = tuple((kb, g) for kb in (0.3, 1.0) for g in (0.5, 1.0, 1.5, 2.0, 2.5, 3.0))

    @staticmethod
    def spring(kb, gap, displacement):
        """The dead-zone spring: its corners rounded over a twentieth of the
        clearance (of a thousandth of the displacement scale at least)."""
        return DeadZoneSpring(kb, gap, max(gap, 1e-3 * displacement) / 20)

    def build(self, theta, nominal, s):
        kb, gap = theta[0] * s.stiffness, theta[1] * s.displacement
        return EffectTerms((self.spring(kb, gap, s.displacement),), physical=dict(kb=kb, gap=gap))

    def data_start(self, clues, nominal, scales):
        return backlash_start(clues, scales, self.spring)

    def joint_start(self, clues, nominal, scales, free):
        return backlash_start(clues, scales, self.spring, nominal=nominal, free=free)


class InputSaturation(Effect):
    name = "input_saturation"
    description = "actuator force clipped at +-u_max"
    param_names = ("u_max",)
    limits = ((0.05, 1.5),)
    listed_starts = ((0.95,), (0.8,), (0.6,))

    def build(self, theta, nominal, s):
        level = theta[0] * s.u_peak

        def transform(u_fine, fs_fine, periodic):
            return np.clip(u_fine, -level, level)
        return EffectTerms(transform=transform, physical=dict(u_max=level))


class InputDelay(Effect):
    name = "input_delay"
    description = "input delayed by a (fractional) time"
    param_names = ("delay_s",)
    limits = ((-20.0, 200.0),)  # samples at the data rate
    listed_starts = ((0.0,),)

    def build(self, theta, nominal, s):
        tau = theta[0] / s.fs

        def transform(u_fine, fs_fine, periodic):
            return delay_signal(u_fine, tau * fs_fine, periodic)
        return EffectTerms(transform=transform, physical=dict(delay_s=tau))


class SecondMode(Effect):
    # Parametrised by the attached mass (relative to the nominal one), the
    # natural frequency of the attached oscillator (relative to the nominal
    # mode) and its damping ratio: well scaled, and any positive values are
    # a physical structure.
    name = "second_mode"
    description = "a second mass coupled by a spring and a damper"
    param_names = ("m2", "c2", "k2")
    limits = ((1e-3, 5.0), (0.05, 20.0), (1e-3, 1.0))
    listed_starts = tuple((0.2, r, 0.02) for r in (0.5, 0.8, 1.25, 2.0, 3.0))

    def build(self, theta, nominal, s):
        w1 = np.sqrt(max(nominal.stiffness, 1e-12 * s.stiffness) / nominal.mass)
        m2 = theta[0] * nominal.mass
        w2 = theta[1] * w1
        k2 = m2 * w2**2
        c2 = 2 * theta[2] * m2 * w2
        return EffectTerms((CoupledMass(m2, c2, k2),), physical=dict(m2=m2, c2=c2, k2=k2, f2_hz=w2 / (2 * np.pi)))

    def data_start(self, clues, nominal, scales):
        return None if clues.change is None else second_mode_start(clues.change, nominal, self.bounds)

    def joint_start(self, clues, nominal, scales, free):
        if clues.change is None:
            return None
        return second_mode_joint_start(clues.change, nominal, scales, self.bounds, free)


class ViscoelasticMount(Effect):
    # Parametrised by the spring's stiffness relative to the nominal one and
    # the relaxation frequency ks / cs relative to the nominal mode: any
    # positive values are a mount, and the mount matters most with its
    # relaxation near the mode.
    name = "viscoelastic_mount"
    description = "a spring and a damper in series to the ground (Maxwell element)"
    param_names = ("cs", "ks", "f_relax_hz")
    limits = ((1e-3, 5.0), (0.05, 20.0))
    listed_starts = tuple((0.1, r) for r in (0.3, 1.0, 3.0))

    def build(self, theta, nominal, s):
        w1 = np.sqrt(max(nominal.stiffness, 1e-12 * s.stiffness) / nominal.mass)
        ks = theta[0] * max(nominal.stiffness, 1e-12 * s.stiffness)
        relax = theta[1] * w1
        cs = ks / relax
        return EffectTerms((SeriesDamper(cs, ks),), physical=dict(cs=cs, ks=ks, f_relax_hz=relax / (2 * np.pi)))


class StiffnessDriftEffect(Effect):
    name = "stiffness_drift"
    description = "stiffness changing linearly over time"
    param_names = ("rate",)
    limits = ((-1.0, 1.0),)
    listed_starts = ((0.0,),)

    def build(self, theta, nominal, s):
        rate = theta[0] * s.stiffness / s.duration
        return EffectTerms((StiffnessDrift(rate),), physical=dict(rate=rate))


class Recalibration(Effect):
    """The candidate that refits the nominal parameters named in ``free``
    (a subset of :data:`NOMINAL_PARAMETERS`) and adds no physics."""

    name = "recalibration"
    is_recalibration = True
    _LIMITS = {"mass": (-0.9, 10.0), "damping": (-5.0, 5.0), "stiffness": (-5.0, 5.0)}

    def __init__(self, free=NOMINAL_PARAMETERS):
        self.param_names = tuple(name for name in NOMINAL_PARAMETERS if name in free)
        if not self.param_names:
            raise ValueError(f"free must name at least one of {NOMINAL_PARAMETERS}.")
        self.limits = tuple(self._LIMITS[name] for name in self.param_names)
        self.listed_starts = ((0.0,) * len(self.param_names),)
        self.description = "nominal " + ", ".join(self.param_names) + " refitted, no new physics"

    def build(self, theta, nominal, s):
        linear = {name: getattr(nominal, name) + t * recalibration_unit(name, nominal, s)
                  for name, t in zip(self.param_names, theta)}
        return EffectTerms(linear=linear, physical=dict(linear))

    def data_start(self, clues, nominal, scales):
        if not clues.change:
            return None
        full = dict(zip(NOMINAL_PARAMETERS, recalibration_start(clues.change, nominal, scales)))
        return np.array([full[name] for name in self.param_names])


class ElementEffect(Effect):
    """A user's force element as a candidate: every parameter is fitted,
    relative to its given value (or on a unit scale when it is zero)."""

    def __init__(self, element):
        self.element = element
        self.p0 = np.asarray(element.parameters(), dtype=float)
        self.scale = np.where(self.p0 != 0, np.abs(self.p0), 1.0)
        self.param_names = tuple(element.param_names)
        self.name = element.name if isinstance(element, CustomForce) else type(element).__name__
        self.description = f"user element {element!r}"
        self.limits = ((-50.0, 50.0),) * self.p0.size
        self.listed_starts = ((0.0,) * self.p0.size,)

    def build(self, theta, nominal, s):
        p = self.p0 + theta * self.scale
        if isinstance(self.element, CustomForce):
            element = self.element.with_params(p)
        else:  # a built-in element's parameters are its constructor's arguments
            element = type(self.element)(*p)
        return EffectTerms((element,), physical=dict(zip(self.param_names, p)))


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


_BUILT_IN = (Hysteresis, CubicSpring, QuadraticSpring, DryFriction, QuadraticDamper, Backlash, InputSaturation,
             InputDelay, SecondMode, StiffnessDriftEffect, Recalibration)
#: The names of the built-in effects, in the order a diagnosis fits them.
BUILT_IN = tuple(cls.name for cls in _BUILT_IN)
#: Effects known by name but not tried unless listed in ``effects=``: the
#: benchmark families have not been run with them among the candidates.
_BY_REQUEST = (ViscoelasticMount,)


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


def make_effect(effect):
    """An :class:`Effect` from a built-in name, a force element or an Effect."""
    if isinstance(effect, Effect):
        return effect
    if isinstance(effect, str):
        table = {cls.name: cls for cls in _BUILT_IN + _BY_REQUEST}
        if effect not in table:
            raise ValueError(
                f"unknown effect {effect!r}; the built-in effects are {list(table)} "
                "(or pass a ForceElement instance or an Effect as your own candidate)."
            )
        return table[effect]()
    if isinstance(effect, ForceElement):
        return ElementEffect(effect)
    raise TypeError(
        f"effects must hold effect names (see default_effects()), ForceElement or Effect "
        f"instances, got {effect!r}."
    )
