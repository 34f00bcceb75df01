"""A lumped nominal's masses and springs updated on the lowest measured
level: the model update a structural engineer makes before looking for a
nonlinearity.

A simulator built from drawings has masses and stiffnesses 10-30 % off.
The error that leaves is linear, at every level, and far larger than a
joint's nonlinearity: with it, a force law at a wrong place explains more
than the right one (the structures of ``gap_withheld.py --family s`` with
every mass and spring 10-30 % off: 1 of 8 right before this update).  The
first-order modal corrections of
:class:`~sklearn_pnlss.gap.connections.recalibrate.ModalCorrection` keep
each mode's shape; a mass or a spring that is off turns the shapes too.

The structure's elements are read off its matrices: each diagonal mass,
each off-diagonal stiffness a spring between two points, each row's sum a
spring to the ground; and each mode's damping ratio has a factor of its
own.  Damping is what a nominal knows least, and where it is not free the
misfit of a joint's friction, whose equivalent damping is largest at the
lowest level, went into the stiffnesses (a friction between two masses of
a chain was then placed at a mass and the ground).  Their factors are fitted to the frequency response
of the lowest level (the structure closest to linear), in two stages:

1. the natural frequencies: the nominal's modes are paired in order with
   the modes read off the measured response (the poles that recur in
   subspace models of several orders) and their log-ratios fitted; a resonance 15 % off lies many bandwidths away,
   where the response's misfit has local minima (of 40 drawn structures
   10-30 % off, a fit of the response alone ended in one for 9, none after
   this stage);
2. the frequency response itself, from there, each output weighted by its
   noise.

Each change of an element's factor costs a little (``PRICE``): the
frequencies alone leave directions free, and the response at a few sensors
does not see every mass.
"""
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.linalg import eigh
from scipy.optimize import least_squares

from ...physics.structure import SENSOR_KINDS, Structure
from ..modal_nominal import subspace_poles
from .recalibrate import ModalCorrection

__all__ = ["ElementCorrection", "ElementUpdate", "linear_corrections", "updated_elements"]

#: Price of a change of an element's log-factor, as a residual: a factor e
#: costs as much as a natural frequency 5 % off in the first stage, and a
#: hundredth of the response's rms in the second.
PRICE = (0.05, 0.01)
#: Subspace orders whose poles are compared (from twice the nominal's
#: modes in the band, by two), the relative distance within which a pole
#: recurs, and the damping ratio above which a pole is no mode.
STABLE_ORDERS, STABLE_TOL, MAX_DAMPING = 4, 0.01, 0.2
#: The factors stay within these (masses and springs, damping ratios;
#: either way): beyond them the nominal is not the structure measured, and
#: a fit that goes there is fitting what no linear structure holds (a
#: friction that locks its joint at the lowest level drove masses to
#: factors of e and 1/e with a bound of e).
MAX_FACTOR = (2.0, 4.0)


@dataclass(frozen=True)
class ElementUpdate:
    """A lumped structure's masses and springs, each changed by a factor.

    Attributes
    ----------
    structure : Structure
        A structure with a diagonal mass matrix on its points.
    springs : list of (int, int or None, float)
        ``(i, j, k)``: a spring of stiffness ``k`` between points ``i`` and
        ``j`` (None: the ground); together they make the stiffness matrix.
    """

    structure: Structure
    springs: list
    damping_ratios: np.ndarray

    @classmethod
    def of(cls, structure):
        """The elements of ``structure``, or None where it is not lumped (a
        modal structure, a full mass matrix)."""
        m, k = structure.mass, structure.stiffness
        lumped = (len(m) > 0 and structure.point_matrix.shape == m.shape
                  and np.allclose(structure.point_matrix, np.eye(len(m))) and np.allclose(m, np.diag(np.diag(m))))
        if not lumped:
            return None
        tol = 1e-12 * np.max(np.abs(k), initial=0.0)
        n = len(k)
        springs = [(i, j, -k[i, j]) for i in range(n) for j in range(i + 1, n) if abs(k[i, j]) > tol]
        springs += [(i, None, k[i].sum()) for i in range(n) if abs(k[i].sum()) > tol]
        omega, shapes = _modes(m, k)
        return cls(structure, springs, np.diag(shapes.T @ structure.damping @ shapes) / (2 * omega))

    @property
    def n_params(self):
        return 2 * self.structure.n_dof + len(self.springs)

    @property
    def names(self):
        points = self.structure.points
        return ([f"mass {p}" for p in points]
                + [f"spring {points[i]} - {'ground' if j is None else points[j]}" for i, j, _ in self.springs]
                + [f"damping ratio of mode {i + 1}" for i in range(self.structure.n_dof)])

    @cached_property
    def _directions(self):
        """Each spring's direction as a column (n_dof, n_springs): its
        stiffness matrix is ``k d d^T``."""
        points = self.structure.points
        return np.stack([self.structure.direction(points[i], None if j is None else points[j])
                         for i, j, _ in self.springs], axis=1)

    def matrices(self, theta):
        """The mass and stiffness matrices at the log-factors ``theta``."""
        n, n_springs = self.structure.n_dof, len(self.springs)
        mass = np.diag(np.diag(self.structure.mass) * np.exp(theta[:n]))
        k = np.array([k for _, _, k in self.springs]) * np.exp(theta[n:n + n_springs])
        return mass, (self._directions * k) @ self._directions.T

    def applied(self, theta):
        """The structure with its elements' factors ``exp(theta)``."""
        mass, stiffness = self.matrices(theta)
        omega, shapes = _modes(mass, stiffness)
        zeta = self.damping_ratios * np.exp(theta[-self.structure.n_dof:])
        # modal damping made physical: C = M phi diag(2 zeta omega) phi^T M
        damping = mass @ shapes @ np.diag(2 * zeta * omega) @ shapes.T @ mass
        s = self.structure
        return Structure(mass, damping, stiffness, points=s.points, connections=s.connections)

    def factors(self, theta):
        """Each element's factor by name."""
        return {name: float(np.exp(t)) for name, t in zip(self.names, theta)}


def _modes(mass, stiffness):
    """Natural frequencies (rad/s, ascending) and mass-normalised shapes."""
    w2, shapes = eigh(stiffness, mass)
    return np.sqrt(np.abs(w2)), shapes


def _paired(measured, model):
    """Indices pairing the measured natural frequencies with the model's in
    order (both ascending), the shorter list matched into the longer one
    where the sum of squared log-ratios is least: (measured, model)."""
    a, b = np.log(measured), np.log(model)
    swap = a.size > b.size
    if swap:
        a, b = b, a
    p, q = a.size, b.size
    cost = np.full((p + 1, q + 1), np.inf)
    cost[0] = 0.0
    for i in range(1, p + 1):
        for j in range(i, q + 1):
            # a_i paired with b_j (after the first i-1 pairs in b[:j-1]), or b_j skipped
            cost[i, j] = min(cost[i, j - 1], cost[i - 1, j - 1] + (a[i - 1] - b[j - 1]) ** 2)
    pairs, j = [], q
    for i in range(p, 0, -1):
        while cost[i, j] == cost[i, j - 1]:
            j -= 1
        pairs.append((i - 1, j - 1))
        j -= 1
    first, second = np.array(pairs[::-1]).T
    return (second, first) if swap else (first, second)


def updated_elements(structure, freqs, frf, weights, *, fs, inputs, sensors):
    """The masses and springs of a lumped structure fitted to a measured
    frequency response (see the module's notes).

    Parameters
    ----------
    structure : Structure
        Lumped (:meth:`ElementUpdate.of` is not None).
    freqs : ndarray of shape (n_freqs,)
        Frequencies of the measured response, Hz.
    frf : ndarray of shape (n_freqs, n_outputs, n_inputs), complex
        Measured response from the input forces to the sensors.
    weights : ndarray of shape (n_outputs,)
        Each output's weight (its noise's inverse rms).
    fs : float
        Sampling rate of the records, Hz.
    inputs, sensors : as :class:`~sklearn_pnlss.gap.connections.ConnectionLocator`

    Returns
    -------
    structure : Structure
        The updated structure (``structure`` itself where no update lowers
        the response's misfit).
    factors : dict
        Each element's factor by name (``"mass m0"``, ``"spring m0 - m1"``).
    """
    elements = ElementUpdate.of(structure)
    theta = np.zeros(elements.n_params)
    weighted = frf * weights[None, :, None]
    size = np.sqrt(np.mean(np.abs(weighted) ** 2))

    def response_misfit(t):
        try:
            model = elements.applied(t).frequency_response(freqs, inputs=inputs, sensors=sensors)
        except (ValueError, np.linalg.LinAlgError):
            return np.full(2 * weighted.size + t.size, 1e3)
        e = (model * weights[None, :, None] - weighted).ravel() / size
        return np.concatenate([e.real, e.imag, PRICE[1] * t])

    n_elements = elements.n_params - structure.n_dof
    limit = np.log(np.r_[np.full(n_elements, MAX_FACTOR[0]), np.full(structure.n_dof, MAX_FACTOR[1])])
    bounds = (-limit, limit)

    def natural(t):  # the natural frequencies at log-factors t, rad/s
        return _modes(*elements.matrices(t))[0]

    nominal = natural(theta)
    in_band = (nominal >= 2 * np.pi * freqs.min()) & (nominal <= 2 * np.pi * freqs.max())
    measured = _measured_frequencies(freqs, frf, max(int(in_band.sum()), 1), fs=fs, sensors=sensors)
    if measured is not None:
        pairs = _paired(measured, natural(theta))
        for _ in range(3):  # paired again where the fitted frequencies change the pairing
            theta = least_squares(lambda t, pairs=pairs: np.concatenate(
                [np.log(natural(t)[pairs[1]] / measured[pairs[0]]), PRICE[0] * t]), theta, bounds=bounds).x
            previous, pairs = pairs, _paired(measured, natural(theta))
            if all(np.array_equal(a, b) for a, b in zip(previous, pairs)):
                break
    theta = least_squares(response_misfit, theta, bounds=bounds, method="trf").x
    if np.sum(response_misfit(theta) ** 2) >= np.sum(response_misfit(np.zeros_like(theta)) ** 2):
        theta = np.zeros_like(theta)
    return (structure if not np.any(theta) else elements.applied(theta)), elements.factors(theta)


def _measured_frequencies(freqs, frf, n_modes, *, fs, sensors):
    """Natural frequencies (rad/s) read off the response from the first
    input, every output as an acceleration: the poles of subspace models
    of ``STABLE_ORDERS`` orders around twice ``n_modes`` that recur in all
    of them within ``STABLE_TOL`` (a stabilisation diagram's stable poles:
    the least damped poles of one order held a spurious one and missed a
    mode the sensors hardly see); None where none recurs."""
    w = 2 * np.pi * freqs
    s = 1j * w[:, None]
    powers = np.array([SENSOR_KINDS.index(kind) for _, kind in sensors])
    acceleration = frf[:, :, 0] * s ** (2 - powers)
    found = []
    for order in 2 * n_modes + 2 * np.arange(STABLE_ORDERS):
        if order >= w.size:
            break
        poles = subspace_poles(w, acceleration, order, fs)
        poles = poles[(poles.imag > 0) & (poles.imag >= w.min()) & (poles.imag <= w.max())
                      & (-poles.real < MAX_DAMPING * np.abs(poles))]
        found.append(np.sort(np.abs(poles)))
    if not found:
        return None
    stable = [p for p in found[0] if all(np.any(np.abs(q / p - 1) < STABLE_TOL) for q in found[1:])]
    return np.array(stable) if stable else None


class ElementCorrection:
    """Small changes of a lumped structure's elements, to first order: its
    masses, springs and modal damping ratios (as :class:`ElementUpdate`),
    fitted with a connection's force law over every level.

    The counterpart of
    :class:`~sklearn_pnlss.gap.connections.recalibrate.ModalCorrection`
    for a structure whose elements are known: an update on the lowest level
    alone takes in what a nonlinearity does there (a friction that nearly
    locks its joint drove the joint's spring and a mass to their bounds),
    and only a fit with the law, level by level, gives it back.  A
    structure's elements also bind its modes to each other, where free
    modes take in part of a law's action.

    Parameters
    ----------
    structure : Structure
        Lumped (:meth:`ElementUpdate.of` is not None).
    freqs : ndarray of shape (n_freqs,)
        The band's frequencies, Hz.
    inputs, sensors : as :class:`~sklearn_pnlss.gap.connections.ConnectionLocator`
    """

    #: Log-factor step of the response's derivatives by differences.
    STEP = 1e-6

    def __init__(self, structure, freqs, *, inputs, sensors):
        self.elements = ElementUpdate.of(structure)
        theta = np.zeros(self.elements.n_params)

        def response(t):
            return self.elements.applied(t).frequency_response(freqs, inputs=inputs, sensors=sensors)

        base = response(theta)
        self.jacobian = np.stack([(response(self.STEP * e) - base) / self.STEP for e in np.eye(theta.size)],
                                 axis=3)

    @property
    def n_params(self):
        return self.elements.n_params

    # the design columns from ``jacobian``, as the modes' are
    columns = ModalCorrection.columns

    def applied(self, theta):
        """The structure with its elements' factors ``exp(theta)``."""
        return self.elements.applied(np.asarray(theta, float))


def linear_corrections(structure, freqs, *, inputs, sensors):
    """The first-order linear corrections a law is fitted with: a lumped
    structure's elements (:class:`ElementCorrection`), else its in-band
    modes (:class:`~sklearn_pnlss.gap.connections.recalibrate.ModalCorrection`)."""
    if ElementUpdate.of(structure) is not None:
        return ElementCorrection(structure, freqs, inputs=inputs, sensors=sensors)
    return ModalCorrection(structure, freqs, inputs=inputs, sensors=sensors)
