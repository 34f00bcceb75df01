"""What a candidate effect is: its parameters, their bounds and starts, what
it adds to the nominal simulator, and how it composes with the nominal's
refit and with a channel delay.

An effect is described by a few dimensionless parameters ``theta`` that are
turned into physical values with the scales of the measured data (input force
rms ``F``, displacement rms ``Y``, velocity rms ``V``, duration ``T``), so
that one optimiser setting fits every effect on every structure, and zero
(or a listed start) means "no effect".  An effect changes the nominal
oscillator (extra force elements, other linear parameters) and may transform
the input before it reaches the structure (saturation, delay).

A new effect is one subclass of :class:`Effect`: its name, parameters,
bounds, starts and :meth:`Effect.build` (and, where the data give one, a
start read from them); the diagnosis needs nothing else.
"""
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

__all__ = ["Scales", "EffectTerms", "Effect", "NOMINAL_PARAMETERS", "recalibration_unit"]

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


def recalibration_unit(name, nominal, scales):
    """Change of the nominal parameter ``name`` per unit of its ``theta``
    in a recalibration: the mass relative to its own value, the damping and
    the stiffness on the scale of the data (``F / V``, ``F / Y``).  The one
    place this scaling is written: the recalibration's build, the missing
    force's columns and the stiffness change's basis all read it."""
    if name == "mass":
        return nominal.mass
    if name == "damping":
        return scales.force / scales.velocity
    if name == "stiffness":
        return scales.stiffness
    raise ValueError(f"{name!r} is no nominal parameter; they are {NOMINAL_PARAMETERS}.")


class EffectTerms(NamedTuple):
    """What an effect adds to the nominal simulator at one ``theta``.

    Attributes
    ----------
    forces : tuple of ForceElement
        Extra force elements.
    linear : dict
        Changed linear parameters (``mass``, ``damping``, ``stiffness``).
    transform : callable or None
        ``f(u_fine, fs_fine, periodic)`` applied to the input at the
        integration rate (saturation, delay).
    physical : dict
        The physical parameter values reported.
    """

    forces: tuple = ()
    linear: dict = {}
    transform: object = None
    physical: dict = {}


def _then(first, second):
    """Two input transforms (either may be None) applied one after the other."""
    if first is None or second is None:
        return second if first is None else first

    def both(u, fs, periodic):
        return second(first(u, fs, periodic), fs, periodic)
    return both


class Effect:
    """One candidate effect (subclass it to add one).

    A subclass sets the class attributes and :meth:`build`; it may read a
    start off the training data (:meth:`data_start`) and, for a stateless
    force, a start together with the nominal's errors
    (:meth:`joint_start`).

    Attributes
    ----------
    name : str
        Name used in reports.
    description : str
        One line saying what the effect is.
    param_names : tuple of str
        Names of the physical parameters reported.
    limits : tuple of (float, float)
        Bounds of each component of ``theta``.
    listed_starts : tuple of tuple
        Starting points of ``theta`` tried on every data set (the best by
        training error is refined).
    is_recalibration : bool
        Whether the effect only refits the nominal parameters.

    Examples
    --------
    A stop engaged beyond twice the rms displacement, its stiffness fitted
    on the scale of the data's (``theta = 1``: the rms force per rms
    displacement); pass ``SoftStop()`` in ``GapDiagnosis(effects=...)``,
    which frees the nominal's parameters and a channel delay with it:

    >>> from sklearn_pnlss.gap import Effect, EffectTerms, Scales
    >>> from sklearn_pnlss.physics import DeadZoneSpring, Oscillator
    >>> class SoftStop(Effect):
    ...     name = "soft_stop"
    ...     description = "a spring engaged beyond twice the rms displacement"
    ...     param_names = ("k_stop",)
    ...     limits = ((0.0, 20.0),)
    ...     listed_starts = ((0.5,), (2.0,))
    ...
    ...     def build(self, theta, nominal, scales):
    ...         k = theta[0] * scales.stiffness
    ...         stop = DeadZoneSpring(k, 2 * scales.displacement, 0.1 * scales.displacement)
    ...         return EffectTerms(forces=(stop,), physical=dict(k_stop=k))
    >>> scales = Scales(force=50.0, displacement=1e-3, velocity=0.1, duration=40.0, u_peak=150.0, fs=750.0)
    >>> osc, transform, physical = SoftStop().simulator([2.0], Oscillator(2.0, 10.0, 5e4), scales)
    >>> float(physical["k_stop"]), osc.forces[0].gap
    (100000.0, 0.002)
    """

    name = None
    description = ""
    param_names = ()
    limits = ()
    listed_starts = ((),)
    is_recalibration = False

    def build(self, theta, nominal, scales):
        """:class:`EffectTerms` at ``theta``; ValueError where ``theta`` is
        not physical."""
        raise NotImplementedError

    def data_start(self, clues, nominal, scales):
        """A start read off the training data before any fit, or several
        (rows), or None (see :mod:`sklearn_pnlss.gap.candidates.clues`)."""
        return None

    def joint_start(self, clues, nominal, scales, free):
        """A start of ``theta`` followed by that of the freed nominal
        parameters ``free``, read off the training data (rows for
        several), or None."""
        return None

    # -- derived ------------------------------------------------------------
    @property
    def bounds(self):
        """Lower and upper bounds of ``theta`` (arrays)."""
        lo, hi = zip(*self.limits) if self.limits else ((), ())
        return np.array(lo, float), np.array(hi, float)

    @property
    def starts(self):
        """The listed starting points (arrays)."""
        return [np.asarray(s, float) for s in self.listed_starts]

    @property
    def n_params(self):
        return len(self.param_names)

    @property
    def parts(self):
        """The names of the single effects it is made of (see :meth:`plus`)."""
        return [self.name]

    def data_starts(self, clues, nominal, scales):
        """Starting points read from the data (empty without clues or a
        data start), inside the bounds."""
        if clues is None:
            return []
        theta = self.data_start(clues, nominal, scales)
        if theta is None:
            return []
        lower, upper = self.bounds
        return [np.clip(t, lower, upper) for t in np.atleast_2d(theta) if np.all(np.isfinite(t))]

    def simulator(self, theta, nominal, scales):
        """The nominal oscillator with the effect added: ``(oscillator,
        input transform, physical parameters)``; ValueError when ``theta``
        is not physical."""
        terms = self.build(np.asarray(theta, float), nominal, scales)
        osc = nominal.with_forces(nominal.forces + tuple(terms.forces), **terms.linear)
        return osc, terms.transform, terms.physical

    # -- composition ----------------------------------------------------------
    def with_recalibration(self, recalibration):
        """The effect with the nominal parameters ``recalibration`` refits
        (a :class:`~sklearn_pnlss.gap.candidates.effects.Recalibration`)
        free too; ``theta`` is the effect's followed by the
        recalibration's."""
        return _WithRecalibration(self, recalibration)

    def plus(self, other):
        """Both effects at once (``theta``: this one's, then ``other``'s,
        which starts at its first listed start): an effect the best single
        one leaves room for, added to it."""
        return _Together(self, other)

    def with_delay(self, delay, start):
        """The effect with a channel delay free too (``delay``, an
        :class:`~sklearn_pnlss.gap.candidates.effects.InputDelay`), starting
        at ``start`` (samples): the measurement chain's delay, fitted with
        every candidate once found."""
        return _WithDelay(self, delay, start)

    def variant(self, *, starts=None, data_starts=None, **labels):
        """The same effect with other listed ``starts`` and/or fixed
        ``data_starts`` (rows; empty for none), or another ``name``,
        ``description`` or ``is_recalibration``: a fit carried on from
        where it stopped, or relabelled."""
        return _Variant(self, starts, data_starts, labels)

    def __repr__(self):
        return f"<{type(self).__name__} {self.name!r}>"


class _Combined(Effect):
    """An effect with ``extra``'s parameters appended to its ``theta``: the
    forces of both, the linear changes of both, the effect's input transform
    then the extra's, and both sets of physical values.  ``theta`` is split
    by the effect's own fitted parameters (its bounds), not by the
    parameters it reports: an effect may report more or fewer."""

    def __init__(self, effect, extra, extra_start):
        self.effect, self.extra = effect, extra
        self.extra_start = np.atleast_1d(np.asarray(extra_start, float))
        self.name, self.description = effect.name, effect.description
        self.is_recalibration = effect.is_recalibration
        self.param_names = effect.param_names + extra.param_names
        self._n = effect.bounds[0].size

    def build(self, theta, nominal, scales):
        own = self.effect.build(theta[:self._n], nominal, scales)
        more = self.extra.build(theta[self._n:], nominal, scales)
        return EffectTerms(tuple(own.forces) + tuple(more.forces), {**own.linear, **more.linear},
                           _then(own.transform, more.transform), {**own.physical, **more.physical})

    @property
    def bounds(self):
        (lo, hi), (x_lo, x_hi) = self.effect.bounds, self.extra.bounds
        return np.concatenate([lo, x_lo]), np.concatenate([hi, x_hi])

    @property
    def starts(self):
        return [np.concatenate([s, self.extra_start]) for s in self.effect.starts]


class _Together(_Combined):
    def __init__(self, first, second):
        super().__init__(first, second, second.starts[0])
        self.name = f"{first.name} + {second.name}"
        self.description = f"{first.description}; {second.description}"

    @property
    def parts(self):
        return [*self.effect.parts, self.extra.name]


class _WithRecalibration(_Combined):
    def __init__(self, effect, recalibration):
        super().__init__(effect, recalibration, recalibration.starts[0])

    def data_start(self, clues, nominal, scales):
        # the effect's own data start (or its first listed one) with the
        # nominal parameters as the stiffness change suggests
        effect, recal, n = self.effect, self.extra, self._n
        free = recal.param_names
        own = effect.data_starts(clues, nominal, scales) or effect.starts[:1]
        refit = recal.data_starts(clues, nominal, scales) or recal.starts[:1]
        starts = [np.concatenate([own[0], refit[0]])]
        # effect and nominal errors together, from the missing force, with
        # all the freed parameters and with fewer: the mass error is the
        # worst determined (a strong nonlinearity's harmonics beyond the
        # derivatives' band leak into it), and the simulation error picks
        # among the starts
        for subset in dict.fromkeys((free, tuple(p for p in free if p != "mass"), ())):
            joint = effect.joint_start(clues, nominal, scales, subset)
            for row in [] if joint is None else np.atleast_2d(joint):  # a joint start may give several
                theta = np.zeros(n + len(free))
                theta[:n] = row[:n]
                theta[[n + free.index(p) for p in subset]] = row[n:]
                starts.append(theta)
        return np.array(starts)


class _WithDelay(_Combined):
    def data_start(self, clues, nominal, scales):
        own = self.effect.data_starts(clues, nominal, scales)
        return np.array([np.append(t, self.extra_start) for t in own]) if own else None


class _Variant(Effect):
    """``effect`` with other starts or labels (see :meth:`Effect.variant`)."""

    def __init__(self, effect, starts, data_starts, labels):
        unknown = set(labels) - {"name", "description", "is_recalibration"}
        if unknown:
            raise TypeError(f"variant() got unexpected labels {sorted(unknown)}.")
        self.effect, self._starts, self._data_starts = effect, starts, data_starts
        self.name = labels.get("name", effect.name)
        self.description = labels.get("description", effect.description)
        self.is_recalibration = labels.get("is_recalibration", effect.is_recalibration)
        self.param_names = effect.param_names

    def build(self, theta, nominal, scales):
        return self.effect.build(theta, nominal, scales)

    @property
    def bounds(self):
        return self.effect.bounds

    @property
    def starts(self):
        return self.effect.starts if self._starts is None else [np.asarray(s, float) for s in self._starts]

    def data_start(self, clues, nominal, scales):
        if self._data_starts is None:
            return self.effect.data_start(clues, nominal, scales)
        return np.array(self._data_starts) if len(self._data_starts) else None

    def joint_start(self, clues, nominal, scales, free):
        if self._data_starts is None:
            return self.effect.joint_start(clues, nominal, scales, free)
        return None
