"""The force laws a connection is tried with, each linear in its parameters.

A law is a stiffness and a damping change at the connection (the linear
part, which a nominal read at another level always needs) plus at most one
nonlinear element of the library with a unit coefficient: its force on the
measured relative motion is one regressor, and the fitted coefficient is the
element's physical parameter.  The force is the integrator's own
(:meth:`~sklearn_pnlss.physics.Oscillator.restoring_force` of the element),
smoothing included, so a law read here simulates as fitted.

A clearance enters nonlinearly; it is profiled over ``BACKLASH_GAPS``
(multiples of the relative displacement's rms), each gap one law.  So does the
loop of a hysteresis: a Bouc-Wen element with ``nu = 1``, whose force grows
along the motion at the rate ``alpha - b z`` while it loads (``b =
beta (gamma + delta)``) and ``alpha - b' z`` while it unloads (``b' =
beta (gamma - delta)``).  It is profiled over its slip displacement
``1 / b`` (``SLIP_DISPLACEMENTS``) and the ratio ``b' / b``
(``UNLOADING_RATES``): 0 is a smoothed Jenkins element (a spring ``alpha``
in series with a dry-friction slider that holds at most ``alpha / b``,
unloading along the stuck stiffness: a bolted joint that sticks and
slips), 1 a loop that softens alike both ways, 4 the Bouc-Wen benchmark's
shape (unloading stiffer than the stuck stiffness).  With the law's own
stiffness change near ``-alpha`` a Jenkins joint leaves the lowest
level's nominal as it was and softens and damps the structure as the level
rises.  Its force depends on the motion's history and is integrated along
the measured record
(:func:`~sklearn_pnlss.physics.hysteresis_path.bouc_wen_along`); a fit by
simulation frees ``beta`` and ``delta`` (``gamma`` kept), so every loop of
``nu = 1`` is within its reach.  Its ``alpha`` is never negative (see
``ForceLaw.nonnegative``): a passive joint's loop dissipates.
"""
from dataclasses import dataclass
from itertools import product

import numpy as np

from ...physics.forces import (BoucWen, CoulombFriction, CubicStiffness, DeadZoneSpring, QuadraticDamping,
                               QuadraticStiffness)
from ...physics.hysteresis_path import bouc_wen_along
from ...physics.oscillator import Oscillator

__all__ = ["ForceLaw", "force_laws", "LAW_NAMES"]

#: The laws tried by default: names shared with the single-mass effects.
LAW_NAMES = ("linear", "cubic_stiffness", "quadratic_stiffness", "coulomb_friction", "quadratic_damping",
             "backlash", "hysteresis")
#: Clearances a backlash is profiled over, in rms relative displacements:
#: from a clearance that most of the motion crosses to one only its peaks
#: reach (a multisine's peaks sit near three rms).
BACKLASH_GAPS = (0.25, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0)
#: Slip displacements ``1 / b`` a hysteresis is profiled over, in rms
#: relative displacements: from a joint that slips through most of the
#: motion (a dry friction with a stiff contact) to a loop that only bends
#: at the peaks of the highest level.
SLIP_DISPLACEMENTS = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)
#: Unloading rates ``b' / b`` a hysteresis is profiled over: a Jenkins
#: element, a symmetric loop, the Bouc-Wen benchmark's shape.
UNLOADING_RATES = (0.0, 1.0, 4.0)
#: Coulomb friction is smoothed over this share of the rms relative velocity
#: (as the single-mass effect is): a sign function at the velocities that
#: carry the response, smooth for Newton's method.
FRICTION_SMOOTHING = 0.01


@dataclass(frozen=True)
class ForceLaw:
    """A connection's force law, linear in its coefficients.

    Attributes
    ----------
    name : str
        The law's name (one of :data:`LAW_NAMES`).
    element : ForceElement or None
        The nonlinear element with a unit coefficient (None: linear only).
    coefficient : str or None
        The element's parameter the coefficient is.
    fixed : dict
        The element's parameters that are not fitted (a clearance, a
        smoothing), physical units.
    profiled : tuple of str
        The parameters of ``fixed`` profiled on a grid here and freed in a
        fit by simulation (a clearance; a hysteresis' ``beta`` and
        ``delta``).
    nonnegative : tuple of str
        The parameters that cannot be negative: a clearance; a hysteresis'
        stuck stiffness ``alpha`` (below zero its loop runs the other way
        round and gives energy back: no joint does) and ``beta``.
    """

    name: str
    element: object = None
    coefficient: str = None
    fixed: dict = None
    profiled: tuple = ()
    nonnegative: tuple = ()

    @property
    def param_names(self):
        """Names of the fitted coefficients, in regressor order."""
        return ("stiffness", "damping") + (() if self.element is None else (self.coefficient,))

    def regressors(self, d, v):
        """The law's regressors on a relative displacement ``d`` and velocity
        ``v`` (arrays of one length): columns of the force per unit
        coefficient."""
        columns = [d, v]
        if isinstance(self.element, BoucWen):  # a force with a history: along the (periodic) record
            e = self.element
            columns.append(bouc_wen_along(d, e.alpha, e.beta, e.gamma, e.delta))
        elif self.element is not None:
            columns.append(Oscillator(1.0, 0.0, 0.0, (self.element,)).restoring_force(d, v))
        return np.stack(columns, axis=-1)

    def parameters(self, coefficients):
        """The physical parameters at ``coefficients`` (fixed ones included)."""
        return {**dict(zip(self.param_names, map(float, coefficients))), **(self.fixed or {})}

    @property
    def free_names(self):
        """The parameters a fit by simulation frees: the coefficients and
        those profiled on a grid here."""
        return self.param_names + tuple(self.profiled)

    def element_with(self, parameters):
        """The nonlinear element at these physical ``parameters`` (None for
        the linear law); a parameter not given takes the element's default
        (a backlash's corner width follows its clearance)."""
        if self.element is None:
            return None
        return type(self.element)(**{n: parameters[n] for n in self.element.param_names if n in parameters})


def force_laws(names, displacement_rms, velocity_rms):
    """The laws named in ``names`` for a connection whose relative motion
    has these rms values (a backlash gives one law per profiled gap, a
    hysteresis one per profiled slip displacement and unloading rate).

    Parameters
    ----------
    names : sequence of str
        From :data:`LAW_NAMES`.
    displacement_rms, velocity_rms : float
        Rms of the connection's relative displacement and velocity, m and m/s.

    Returns
    -------
    laws : list of ForceLaw
    """
    unknown = [n for n in names if n not in LAW_NAMES]
    if unknown:
        raise ValueError(f"unknown force laws {unknown}; the laws are {list(LAW_NAMES)}.")
    v_smooth = float(max(FRICTION_SMOOTHING * velocity_rms, 1e-300))
    single = {
        "linear": ForceLaw("linear"),
        "cubic_stiffness": ForceLaw("cubic_stiffness", CubicStiffness(1.0), "k3"),
        "quadratic_stiffness": ForceLaw("quadratic_stiffness", QuadraticStiffness(1.0), "k2"),
        "coulomb_friction": ForceLaw("coulomb_friction", CoulombFriction(1.0, v_smooth), "fc",
                                     dict(v_smooth=v_smooth)),
        "quadratic_damping": ForceLaw("quadratic_damping", QuadraticDamping(1.0), "c2"),
    }
    laws = []
    for name in names:
        if name == "backlash":
            for g in BACKLASH_GAPS:
                gap = float(g * displacement_rms)
                laws.append(ForceLaw("backlash", DeadZoneSpring(1.0, gap), "kb", dict(gap=gap), ("gap",), ("gap",)))
        elif name == "hysteresis":
            for slip, ratio in product(SLIP_DISPLACEMENTS, UNLOADING_RATES):
                # beta = b, so gamma and delta hold the shape: (1 +- ratio) / 2
                shape = dict(beta=float(1.0 / (slip * displacement_rms)), gamma=(1.0 + ratio) / 2,
                             delta=(1.0 - ratio) / 2, nu=1.0)
                laws.append(ForceLaw("hysteresis", BoucWen(1.0, **shape), "alpha", shape, ("beta", "delta"),
                                     ("alpha", "beta")))
        else:
            laws.append(single[name])
    return laws
