"""The nominal's modes recalibrated on the lowest measured level: a model
update before the diagnosis, so that the error left is the connection's.

A simulator's masses and stiffnesses are rarely right to 10 %; the error
that leaves is linear and present at every level, and a force law at a
connection would absorb part of it in place of the effect (a chain whose
springs were 10-30 % off had its cubic spring named as dry friction at the
wrong place).  The lowest level is the structure closest to linear: there
each mode's frequency, damping ratio and modal scale (the size of its
shape) are refitted to the measured frequency response, the shapes'
directions kept, as a modal update does.
"""
import numpy as np
from scipy.linalg import eigh
from scipy.optimize import least_squares

from ...physics.structure import SENSOR_KINDS, Structure

__all__ = ["modal_form", "recalibrated", "ModalCorrection"]

#: Modes refitted: those within this factor of the band's edges (a mode
#: far outside shapes the band by its static or mass-like tail only, which
#: its frequency and scale trade against each other).
BAND_REACH = 2.0


def modal_form(structure):
    """The structure in modal coordinates: mass-normalised modes at every
    point, modal damping ratios from the damping matrix's diagonal in the
    modes (off-diagonal coupling dropped, as proportional damping has none).
    A structure already in modal form is returned as it is."""
    m, c, k = structure.mass, structure.damping, structure.stiffness
    if np.allclose(m, np.eye(len(m))) and np.allclose(c, np.diag(np.diag(c))) and np.allclose(k, np.diag(np.diag(k))):
        return structure
    w2, phi = eigh(k, m)
    if np.any(w2 <= 0):
        raise ValueError("the nominal has a rigid-body or unstable mode (stiffness not positive definite); "
                         "recalibrate=False, or give it a support.")
    omega = np.sqrt(w2)
    zeta = np.diag(phi.T @ c @ phi) / (2 * omega)
    return Structure.from_modes(omega / (2 * np.pi), zeta, structure.point_matrix @ phi, points=structure.points,
                                connections=structure.connections, coupled=np.ones(omega.size, bool))


def _modal_terms(freqs, omega, zeta, shapes_out, shapes_in, powers):
    """Each mode's term at ``freqs``, (n_freqs, n_outputs, n_inputs,
    n_modes), and its denominator (n_freqs, n_modes)."""
    s = 2j * np.pi * freqs[:, None]
    den = omega**2 + 2 * zeta * omega * s + s**2
    terms = np.einsum("om,im,fm->foim", shapes_out, shapes_in, 1.0 / den)
    return terms * (s ** powers[None, :])[:, :, None, None], den


def _modal_parameters(modal):
    omega = np.sqrt(np.diag(modal.stiffness))
    return omega, np.diag(modal.damping) / (2 * omega), modal.point_matrix


class ModalCorrection:
    """Small changes of a structure's in-band modes, to first order: the
    nominal's linear error, shared by every level, fitted together with a
    connection's force law (a law fitted alone absorbs it in part).

    Each in-band mode has three parameters, the logarithms of the factors
    on its frequency, damping ratio and shape scale.

    Parameters
    ----------
    structure : Structure
    freqs : ndarray of shape (n_freqs,)
        The band's frequencies, Hz.
    inputs, sensors : as :class:`~sklearn_pnlss.gap.connections.ConnectionLocator`
    """

    def __init__(self, structure, freqs, *, inputs, sensors):
        self.modal = modal_form(structure)
        omega, zeta, shapes = _modal_parameters(self.modal)
        w_lo, w_hi = 2 * np.pi * freqs.min() / BAND_REACH, 2 * np.pi * freqs.max() * BAND_REACH
        self.modes = np.flatnonzero((omega >= w_lo) & (omega <= w_hi))
        rows = [self.modal.points.index(p) for p, _ in sensors]
        cols = [self.modal.points.index(p) for p in inputs]
        powers = np.array([SENSOR_KINDS.index(kind) for _, kind in sensors])
        w, z = omega[self.modes], zeta[self.modes]
        s = 2j * np.pi * freqs[:, None]
        # each mode's term and its derivatives by the three logarithms
        term, den = _modal_terms(freqs, w, z, shapes[rows][:, self.modes], shapes[cols][:, self.modes], powers)
        d_freq = -term * ((2 * w**2 + 2 * z * w * s) / den)[:, None, None, :]
        d_damp = -term * ((2 * z * w * s) / den)[:, None, None, :]
        self.jacobian = np.concatenate([d_freq, d_damp, 2 * term], axis=3)

    @property
    def n_params(self):
        return 3 * self.modes.size

    def columns(self, U):
        """The changes of the outputs' spectra per parameter for input
        spectra ``U`` (n_freqs, n_inputs): (n_freqs, n_outputs, n_params)."""
        return np.einsum("foip,fi->fop", self.jacobian, U)

    def applied(self, theta):
        """The structure with the changes ``theta`` made exactly."""
        if not np.any(theta):
            return self.modal
        omega, zeta, shapes = _modal_parameters(self.modal)
        a, b, c = np.split(np.asarray(theta, float), 3)
        omega, zeta, shapes = omega.copy(), zeta.copy(), shapes.copy()
        omega[self.modes] *= np.exp(a)
        zeta[self.modes] *= np.exp(b)
        shapes[:, self.modes] *= np.exp(c)
        return Structure.from_modes(omega / (2 * np.pi), zeta, shapes, points=self.modal.points,
                                    connections=self.modal.connections, coupled=self.modal.coupled)


def recalibrated(structure, freqs, frf, weights, *, inputs, sensors):
    """The structure's in-band modes refitted to a measured frequency response.

    Parameters
    ----------
    structure : Structure
    freqs : ndarray of shape (n_freqs,)
        Frequencies of the measured response, Hz.
    frf : ndarray of shape (n_freqs, n_outputs, n_inputs), complex
        Measured response from the input forces to the sensors.
    weights : ndarray of shape (n_outputs,)
        Each output's weight (its noise's inverse rms).
    inputs, sensors : as :class:`~sklearn_pnlss.gap.connections.ConnectionLocator`

    Returns
    -------
    structure : Structure
        In modal form, each in-band mode's frequency, damping ratio and
        shape scale refitted.
    """
    modal = modal_form(structure)
    omega, zeta, shapes = _modal_parameters(modal)
    rows = np.array([modal.points.index(p) for p, _ in sensors])
    cols = np.array([modal.points.index(p) for p in inputs])
    powers = np.array([SENSOR_KINDS.index(kind) for _, kind in sensors])
    w_lo, w_hi = 2 * np.pi * freqs.min() / BAND_REACH, 2 * np.pi * freqs.max() * BAND_REACH
    free = np.flatnonzero((omega >= w_lo) & (omega <= w_hi))
    if free.size == 0:
        return modal
    weighted = frf * weights[None, :, None]

    def model(theta):
        a, b, c = np.split(theta, 3)
        w, z, scale = omega.copy(), zeta.copy(), np.ones(omega.size)
        w[free] *= np.exp(a)
        z[free] *= np.exp(b)
        scale[free] = np.exp(c)
        phi = shapes * scale
        return w, z, phi

    def residuals(theta):
        w, z, phi = model(theta)
        frf = _modal_terms(freqs, w, z, phi[rows], phi[cols], powers)[0].sum(axis=3)
        e = (frf * weights[None, :, None] - weighted).ravel()
        return np.concatenate([e.real, e.imag])

    res = least_squares(residuals, np.zeros(3 * free.size), method="lm", xtol=1e-10, ftol=1e-10)
    if np.sum(res.fun**2) >= np.sum(residuals(np.zeros(3 * free.size)) ** 2):
        return modal
    w, z, phi = model(res.x)
    return Structure.from_modes(w / (2 * np.pi), z, phi, points=modal.points, connections=modal.connections,
                                coupled=modal.coupled)
