"""A located connection fitted by simulation: the structure with its force
law at its place, run to the periodic steady state of every training
record, its parameters refined on the simulation error.

The locator's coefficients come from the measured motion; simulated, the
connection moves the structure itself, and only a simulation says how far
the gap closes.  The error is read where the locator reads it: the lines
of the band, each output weighted by its noise.
"""
import time
import warnings
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ...physics.prewarp import prewarped, rate_correction
from ...physics.resampling import decimate_columns, upsample_fft
from ...physics.structure import SENSOR_KINDS, Connection
from ...utils.threads import each_in_threads
from ..fitting.simulate import FIT_MAX_PERIODS, prime_factors

__all__ = ["BandError", "ConnectionFit", "connected", "fit_connection"]

#: Residual of a trial point whose simulation diverges, relative to the
#: records' weighted size: far above any real misfit, so that the trust
#: region shrinks away from it.
_PENALTY = 1e3


def connected(nominal, place, law, parameters):
    """The nominal with a force law at a place: its element as a
    :class:`~sklearn_pnlss.physics.Connection` and its stiffness and
    damping changes as springs (see :meth:`Structure.with_connections`)."""
    a, b = place
    element = law.element_with(parameters)
    return nominal.with_connections([] if element is None else [Connection(element, a, b)],
                                    springs=[(a, b, parameters["stiffness"], parameters["damping"])])


class BandError:
    """The weighted error of a structure's steady-state simulation at the
    band's lines of periodic records.

    Parameters
    ----------
    spectra : PeriodSpectra
    lines : ndarray of int
        The band's lines.
    weights : ndarray of shape (n_outputs,)
        Each output's weight (its noise's inverse rms).
    inputs, sensors : as :class:`ConnectionLocator`
    oversampling : int
        Integration rate over the data rate (decimated by its prime factors).
    """

    def __init__(self, spectra, lines, weights, inputs, sensors, oversampling):
        self.spectra, self.lines, self.weights = spectra, lines, weights
        self.inputs, self.sensors, self.oversampling = list(inputs), list(sensors), int(oversampling)
        self.u_fine = [np.stack([upsample_fft(np.fft.irfft(U[:, j], spectra.period), oversampling, periodic=True)
                                 for j in range(U.shape[1])], axis=1) for U in spectra.U]
        self.measured = spectra.Y[:, lines] * weights
        self.size = float(np.sqrt(np.mean(np.abs(self.measured) ** 2)))  # the weighted records' rms
        # the integrator's rates made continuous, per line (see
        # physics.prewarp), with the outputs' weights
        fs_fine = spectra.fs * self.oversampling
        self._out_factors = rate_correction(spectra.freqs[lines], fs_fine, self.sensors) * weights
        # a trial point whose sensed displacements run _PENALTY times past
        # the measured ones' is stopped after a period (else it ran every
        # period the steady-state search allows: a second a trial)
        orders = np.array([SENSOR_KINDS.index(kind) for _, kind in self.sensors])
        displacement = np.abs(spectra.Y[:, lines]) / (2 * np.pi * spectra.freqs[lines, None]) ** orders
        self._max_abs = _PENALTY * np.sqrt(2 * np.max(np.sum(displacement**2, axis=1))) / spectra.period
        self.n_simulations = 0
        # each record's last steady state: the next trial point's search
        # starts there (a neighbouring structure's orbit is close to it)
        self.forget_starts()

    def simulate(self, structure):
        """Each record's simulated output spectra at the band's lines,
        weighted: (n_signals, n_lines, n_outputs); FloatingPointError when a
        simulation diverges.

        The structure is simulated prewarped (see
        :mod:`~sklearn_pnlss.physics.prewarp`): the continuous structure's
        response, not Newmark's at a few steps per sample.  Each record's
        steady-state search starts from the last simulated one's, and its
        own is the next search's start."""
        (out, starts), = self._run_side_by_side([structure])
        if out is None:
            raise FloatingPointError("the simulation diverged.")
        self._starts = starts
        return out

    def residuals_around(self, structures):
        """:meth:`residuals` of structures near the last one simulated (a
        Jacobian's steps), all run side by side from its steady states,
        which stay the next search's starts."""
        vectors = [self._residual_vector(out) for out, _ in self._run_side_by_side(structures)]
        return [self.penalty() if e is None else e for e in vectors]

    def _run_side_by_side(self, structures):
        """``(spectra, final states)`` of each structure on every record, run
        side by side in threads (all records of all structures at once: a
        Jacobian's columns keep both cores busy where one structure's three
        records left one idle a third of the time); ``(None, None)`` for
        one that diverges."""
        fs_fine, decimation = self.spectra.fs * self.oversampling, prime_factors(self.oversampling)
        warped = [prewarped(structure, fs_fine) for structure in structures]

        def one(k, u_fine, start):
            if start is not None and start.size != 3 * warped[k].n_dof + 2 * warped[k].n_internal_states:
                start = None
            try:
                with warnings.catch_warnings():
                    # a trial point that does not settle is judged by its misfit
                    warnings.simplefilter("ignore")
                    sim = warped[k].simulate_fine(u_fine, fs=fs_fine, inputs=self.inputs, periodic=True,
                                                  initial_state=start, warn=False, max_periods=FIT_MAX_PERIODS,
                                                  max_abs=self._max_abs)
            except (FloatingPointError, ValueError, np.linalg.LinAlgError):
                return None, None
            y = decimate_columns(warped[k].measure(sim, self.sensors), decimation, periodic=True)
            return np.fft.rfft(y, axis=0)[self.lines] * self._out_factors, sim.final_state

        def run(ks, starts):
            rows = [(k, u, start) for k in ks for u, start in zip(self.u_fine, starts)]
            done = each_in_threads(one, *zip(*rows))
            n = len(self.u_fine)
            return [done[i * n:(i + 1) * n] for i in range(len(ks))]

        self.n_simulations += len(structures)
        results = run(range(len(structures)), self._starts)
        # a start on another structure's orbit (a large one, of a trial
        # point far off) can throw a stiff law off; from rest, once more
        again = [k for k, records in enumerate(results) if not _finite(records)]
        if again and any(s is not None for s in self._starts):
            for k, records in zip(again, run(again, [None] * len(self.u_fine))):
                results[k] = records
        return [(np.array([r[0] for r in records]), [r[1] for r in records]) if _finite(records) else (None, None)
                for records in results]

    def forget_starts(self):
        """The next simulation starts from rest (a new fit's structure is
        not a neighbour of the last one simulated)."""
        self._starts = [None] * len(self.u_fine)

    def residuals(self, structure):
        """Real and imaginary parts of the weighted error, flattened."""
        try:
            e = self._residual_vector(self.simulate(structure))
        except FloatingPointError:
            e = None
        if e is None:
            # its orbit is no start for the next trial point (from there a
            # stiff law ran away at every step of a Jacobian)
            self.forget_starts()
            return self.penalty()
        return e

    def penalty(self):
        """The residuals of a trial point that diverges or runs away: a
        constant far above any real misfit."""
        return np.full(2 * self.measured.size, _PENALTY * self.size)

    def _residual_vector(self, simulated):
        """The weighted error of simulated spectra, flattened; None for a
        diverged (None) or running-away simulation."""
        if simulated is None:
            return None
        e = (simulated - self.measured).reshape(-1)
        if np.sqrt(np.mean(np.abs(e) ** 2)) > _PENALTY * self.size:
            return None
        return np.concatenate([e.real, e.imag])

    def relative(self, simulated):
        """Each record's rms error over its rms output (weighted outputs)."""
        return np.sqrt(np.sum(np.abs(simulated - self.measured) ** 2, axis=(1, 2))
                       / np.sum(np.abs(self.measured) ** 2, axis=(1, 2)))


def _finite(records):
    return all(r[0] is not None and np.all(np.isfinite(r[0])) for r in records)


@dataclass(frozen=True)
class ConnectionFit:
    """A connection fitted by simulation.

    Attributes
    ----------
    candidate : ConnectionCandidate
        Where it started (the locator's fit).
    parameters : dict
        Physical parameters after the fit.
    structure : Structure
        The nominal with the connection.
    train_error : ndarray of shape (n_signals,)
        Each training record's rms simulation error over its rms output in
        the band (outputs weighted by their noise).
    n_simulations : int
        Simulations of the training set used.
    seconds : float
    """

    candidate: object
    parameters: dict
    structure: object
    train_error: np.ndarray
    n_simulations: int
    seconds: float

    @property
    def place(self):
        return self.candidate.place

    @property
    def law(self):
        return self.candidate.law


def fit_connection(nominal, candidate, error, *, scales, max_nfev=20, correction=None):
    """Refine a located connection's parameters by simulation error.

    Parameters
    ----------
    nominal : Structure
    candidate : ConnectionCandidate
    error : BandError
        The training records' error.
    scales : (float, float)
        Rms relative displacement and velocity at the place: the size of a
        stiffness and damping change that matters, where the locator's
        value is zero.
    max_nfev : int, default=20
        Evaluations of the least squares at most (each costs a simulation
        of the training records, and one per parameter for its Jacobian,
        those run side by side).
    correction : ModalCorrection, default=None
        Modal corrections of ``nominal`` (built around it) fitted with the
        connection: the locator's are first-order, and the law's linear
        part trades against them.

    Returns
    -------
    ConnectionFit
    """
    start = time.perf_counter()
    law, p0 = candidate.law, dict(candidate.parameters)
    names = law.free_names
    d_rms, v_rms = scales
    size = error.size
    penalty = np.full(2 * error.measured.size, _PENALTY)  # error.penalty(), relative to size
    # each parameter on the scale of its locator value (a change of its own
    # size), or of the force it adds at the rms motion where that is zero
    typical = {"stiffness": 1.0 / d_rms, "damping": 1.0 / v_rms, "gap": d_rms}
    scale = np.array([abs(p0[n]) if p0[n] != 0 else typical.get(n, 1.0) for n in names])
    n_modal = 0 if correction is None else correction.n_params
    lower = np.full(len(names) + n_modal, -np.inf)
    for name in law.nonnegative:
        i = names.index(name)
        lower[i] = -max(p0[name], 0.0) / scale[i]

    def parameters(theta):
        return {**p0, **{n: float(p0[n] + t * s) for n, t, s in zip(names, theta, scale)}}

    def structure_at(theta):
        base = nominal if not n_modal else correction.applied(theta[len(names):])
        return connected(base, candidate.place, law, parameters(theta[:len(names)]))

    def fun(theta):
        try:
            structure = structure_at(theta)
        except ValueError:  # a correction that is not a structure's
            return penalty.copy()
        return error.residuals(structure) / size

    def jacobian_steps(_, thetas):
        # least_squares's map over a Jacobian's steps (``workers``): the
        # steps simulated side by side, from the point's own steady states
        thetas, structures = list(thetas), []
        for theta in thetas:
            try:
                structures.append(structure_at(theta))
            except ValueError:
                structures.append(None)
        simulated = iter(error.residuals_around([s for s in structures if s is not None]))
        return [next(simulated) / size if s is not None else penalty.copy() for s in structures]

    first = error.n_simulations
    error.forget_starts()
    # the locator's coefficients, and its nonlinear element alone: a large
    # linear change read off the measured motion can make the simulated
    # structure unstable, where the element alone is not
    starts = [np.zeros(len(names) + n_modal)]
    if p0["stiffness"] or p0["damping"]:
        starts.append(-np.array([n in ("stiffness", "damping") for n in names] + [False] * n_modal, float))
    costs = [np.sum(fun(t) ** 2) for t in starts]
    theta0 = starts[int(np.argmin(costs))]
    res = least_squares(fun, theta0, bounds=(lower, np.inf), method="trf", x_scale="jac", diff_step=1e-4,
                        max_nfev=max_nfev, xtol=1e-6, ftol=1e-6, workers=jacobian_steps)
    theta = res.x if np.sum(res.fun**2) < min(costs) else theta0
    best, structure = parameters(theta[:len(names)]), structure_at(theta)
    try:
        train_error = error.relative(error.simulate(structure))
    except (FloatingPointError, ValueError, np.linalg.LinAlgError):
        train_error = np.full(error.measured.shape[0], np.inf)
    if np.any(train_error > _PENALTY):
        train_error = np.full(error.measured.shape[0], np.inf)  # no stable point was found
    return ConnectionFit(candidate, best, structure, train_error, error.n_simulations - first,
                         time.perf_counter() - start)
