"""What the training data say before any fit, to start the candidates.

Two readings of the measurements against the nominal simulator:

* the change of dynamic stiffness at the excited lines (see
  :mod:`sklearn_pnlss.gap.stiffness_start`), which linear candidates (a
  second mode, recalibration) are fitted to first;
* the missing force along the measured motion (see
  :func:`sklearn_pnlss.gap.where.missing_force`), a restoring-force
  surface to which a stateless force law can be fitted directly.

A needle-shaped minimum, such as a stiff backlash spring whose clearance is
near the response's peaks (the response jumps as the spring engages), is
found this way where the simulation-error fit from listed starts settles
far off.
"""
from dataclasses import dataclass

import numpy as np

from .stiffness_start import measured_stiffness_change
from .where import content_limit, missing_force

__all__ = ["DataClues", "read_clues", "backlash_start"]


@dataclass
class DataClues:
    """Readings of the training data that give candidates a start.

    Attributes
    ----------
    change : StiffnessChange or None
        Measured change of dynamic stiffness (None without periodic data).
    displacement, velocity, force : ndarray or None
        The measured motion and the force the nominal simulator misses
        along it (None when it cannot be read).
    """

    change: object = None
    displacement: np.ndarray = None
    velocity: np.ndarray = None
    force: np.ndarray = None


def read_clues(nominal, u_list, y_list, y_nominal, n_periods, period, fs):
    """:class:`DataClues` of the training signals."""
    change = measured_stiffness_change(u_list, y_list, y_nominal, period, fs)
    try:
        y, v, f = missing_force(nominal, u_list, y_list, n_periods, period, fs, content_limit(u_list, fs))
    except ValueError:
        y = v = f = None
    return DataClues(change, y, v, f)


def backlash_start(clues, scales, n_grid=200):
    """``theta = (kb, gap)`` of a dead-zone spring fitted to the missing
    force: for each clearance on a grid up to the largest displacement the
    spring rate follows by linear least squares."""
    if clues.force is None:
        return None
    y, f = clues.displacement, clues.force
    best, best_cost = None, np.sum(f**2)
    for gap in np.linspace(0.0, np.max(np.abs(y)), n_grid, endpoint=False):
        basis = np.sign(y) * np.maximum(np.abs(y) - gap, 0.0)
        bb = basis @ basis
        if bb == 0:
            continue
        kb = (basis @ f) / bb
        cost = np.sum((f - kb * basis) ** 2)
        if cost < best_cost:
            best, best_cost = np.array([kb / scales.stiffness, gap / scales.displacement]), cost
    return best
