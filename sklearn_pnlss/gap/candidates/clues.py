"""What the training data say before any fit, to start the candidates.

Two readings of the measurements against the nominal simulator:

* the change of dynamic stiffness at the excited lines (see
  :mod:`sklearn_pnlss.gap.candidates.stiffness_start`), which linear candidates (a
  second mode, recalibration) are fitted to first;
* the missing force along the measured motion (see
  :func:`sklearn_pnlss.gap.readings.missing_force`), a restoring-force
  surface to which a stateless force law can be fitted directly.

A needle-shaped minimum, such as a stiff backlash spring whose clearance is
near the response's peaks (the response jumps as the spring engages), is
found this way where the simulation-error fit from listed starts settles
far off.
"""
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize_scalar

from ...physics import Oscillator
from .effect import recalibration_unit
from .stiffness_start import measured_stiffness_change
from .trial_columns import TrialColumns
from ..readings import content_limit, missing_force

__all__ = ["DataClues", "read_clues", "backlash_start", "force_law_start"]


@dataclass
class DataClues:
    """Readings of the training data that give candidates a start.

    Attributes
    ----------
    change : StiffnessChange or None
        Measured change of dynamic stiffness (None without periodic data).
    displacement, velocity, acceleration, force : ndarray or None
        The measured motion and the force the nominal simulator misses
        along it (None when it cannot be read).
    """

    change: object = None
    displacement: np.ndarray = None
    velocity: np.ndarray = None
    acceleration: np.ndarray = None
    force: np.ndarray = None


def read_clues(nominal, u_list, y_list, y_nominal, n_periods, period, fs):
    """:class:`DataClues` of the training signals."""
    change = measured_stiffness_change(u_list, y_list, y_nominal, period, fs)
    try:
        y, v, a, f = missing_force(nominal, u_list, y_list, n_periods, period, fs, content_limit(u_list, fs))
    except ValueError:
        y = v = a = f = None
    return DataClues(change, y, v, a, f)


#: The measured motion each recalibrated nominal parameter's change acts on
#: (its force per unit change is this times
#: :func:`~sklearn_pnlss.gap.candidates.effect.recalibration_unit`).
_MOTION_OF = {"mass": "acceleration", "damping": "velocity", "stiffness": "displacement"}


def _linear_columns(clues, nominal, scales, free):
    """The missing force per unit ``theta`` of each freed nominal parameter
    (``free``, in order)."""
    return [recalibration_unit(name, nominal, scales) * getattr(clues, _MOTION_OF[name]) for name in free]


#: Relative changes of the mass around a joint start's own at which the start
#: is solved again with the mass held (see :func:`_along_mass`).
MASS_PROFILE = np.delete(np.round(np.arange(-0.08, 0.0801, 0.005), 4), 16)


def _along_mass(theta, n_effect, clues, nominal, free, solve):
    """``theta``, a joint start with the mass among the freed parameters
    ``free``, and below it the starts solved again with the mass held at
    each :data:`MASS_PROFILE` step from its own (rows; ``theta`` alone
    without the mass).

    The missing force determines the mass worst: a strong nonlinearity's
    harmonics beyond the derivatives' band leak into the acceleration, and
    the spring rate and the stiffness follow the mass's error.  Where the
    simulation error's minimum is narrower than that error (a stiff backlash
    whose response jumps: a joint start 4 % off in mass, stiffness and spring
    rate together, a minimum 0.5 % wide along that line), the simulation
    error picks among the profile's starts.  ``solve(clues, free)`` is the
    joint solve.
    """
    if theta is None or "mass" not in free:
        return theta
    i = n_effect + free.index("mass")
    rest = tuple(p for p in free if p != "mass")
    rows = [theta]
    for step in MASS_PROFILE:
        t = theta[i] + step
        held = solve(replace(clues, force=clues.force - t * nominal.mass * clues.acceleration), rest)
        if held is not None:
            rows.append(np.insert(held, i, t))
    return np.array(rows)


def force_law_start(clues, force_law, nominal, scales, free=()):
    """``theta`` of a force law linear in its one parameter, and of the
    freed nominal parameters, by least squares on the missing force (the
    restoring-force surface method).

    The missing force along the measured motion is what the effect and the
    nominal parameters' errors must supply: ``u - m a - c v - k y =
    t g(y, v) + dm a + dc v + dk y``.  Linear in all of them, so one solve
    gives a start close to the simulation-error optimum even where that
    optimum is far from zero (a strong cubic spring that shifts the
    resonance by half its width: the listed start sits in another basin).

    Parameters
    ----------
    clues : DataClues
    force_law : callable
        ``force_law(y, v, scales)``: the force of the effect at ``t = 1``.
    nominal : Oscillator
    scales : Scales
    free : sequence of str
        Nominal parameters refitted with the effect, in the order of their
        ``theta`` (among :data:`~sklearn_pnlss.gap.candidates.effect.NOMINAL_PARAMETERS`).

    Returns
    -------
    theta : ndarray of shape (1 + len(free),) or None
        None when the missing force cannot be read.  With the mass freed,
        rows: the joint start, then its profile along the mass (see
        :func:`_along_mass`).
    """
    if clues is None or clues.force is None:
        return None

    def solve(clues, free):
        return _force_law_solve(clues, force_law, nominal, scales, free)
    return _along_mass(solve(clues, free), 1, clues, nominal, free, solve)


def _force_law_solve(clues, force_law, nominal, scales, free):
    """:func:`force_law_start`'s one linear solve."""
    columns = [force_law(clues.displacement, clues.velocity, scales)]
    columns += _linear_columns(clues, nominal, scales, free)
    # and a constant: a static force (a force sensor's offset) is no effect
    columns.append(np.ones_like(clues.force))
    A = np.stack(columns, axis=1)
    norms = np.linalg.norm(A, axis=0)
    if np.any(norms == 0):
        return None
    return (np.linalg.lstsq(A / norms, clues.force, rcond=None)[0] / norms)[:-1]


def backlash_start(clues, scales, spring, n_grid=200, nominal=None, free=()):
    """``theta = (kb, gap)`` of a dead-zone spring fitted to the missing
    force, followed by the ``theta`` of the freed nominal parameters
    (``free``, see :func:`_linear_columns`).

    For each clearance on a grid up to the largest displacement the spring
    rate (and the nominal errors) follow by linear least squares; the best
    clearance is then refined between its grid neighbours with the
    candidate's own rounded ``spring(kb, gap, displacement_scale)``.  The grid
    alone leaves the clearance off by up to half a step (0.5 % of a 2.5 mm
    gap), where a stiff spring's jumping response has a simulation error
    20 dB above the noise and a needle-shaped minimum the simulation fit
    does not find from there.  None when no clearance explains more than
    the nominal errors alone.  With the mass freed, rows: the joint start,
    then its profile along the mass (see :func:`_along_mass`; the clearance
    searched there within three grid steps of the joint start's).
    """
    if clues.force is None:
        return None
    grid = np.linspace(0.0, np.max(np.abs(clues.displacement)), n_grid, endpoint=False)
    theta = _backlash_solve(clues, scales, spring, nominal, free, grid)
    if theta is None:
        return None
    near = grid[np.abs(grid - theta[1] * scales.displacement) <= 3.5 * grid[1]]
    return _along_mass(theta, 2, clues, nominal, free,
                       lambda clues, free: _backlash_solve(clues, scales, spring, nominal, free, near))


def _backlash_solve(clues, scales, spring, nominal, free, grid):
    """:func:`backlash_start`'s solve over the evenly spaced clearances
    ``grid``, refined between the best one's neighbours."""
    y, f = clues.displacement, clues.force
    trials = TrialColumns(np.stack(_linear_columns(clues, nominal, scales, free) or [np.zeros_like(f)], 1), f)

    def rounded(gap):
        unit = Oscillator(1.0, 0.0, 0.0, forces=(spring(1.0, gap, scales.displacement),))
        return unit.restoring_force(y, np.zeros_like(y))

    # every clearance's sharp dead zone fitted at once, a few at a time (an
    # array of samples by clearances)
    chunks = np.array_split(grid, max(1, len(grid) // 32))
    costs = np.concatenate([trials.costs(np.sign(y)[:, None] * np.maximum(np.abs(y)[:, None] - chunk, 0.0))
                            for chunk in chunks])
    best = int(np.argmin(costs))
    if not costs[best] < trials.base_cost:
        return None  # no clearance explains more than the nominal errors alone
    best_gap = grid[best]
    step = grid[1] - grid[0]
    gap = minimize_scalar(lambda g: trials.costs(rounded(g))[0], bounds=(max(best_gap - step, 0.0), best_gap + step),
                          method="bounded", options=dict(xatol=1e-6 * step)).x
    coef = trials.solve(rounded(gap))[0]
    # the linear columns are per unit theta: their coefficients are theta
    return np.concatenate([[coef[0] / scales.stiffness, gap / scales.displacement], coef[1:1 + len(free)]])
