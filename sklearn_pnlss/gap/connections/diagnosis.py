"""The gap diagnosis of a structure: where the simulator misses the
measurements, which force law there explains it, and how far the gap closes
once the connection is simulated.

Three stages, each a module of its own:

1. locate (:class:`~sklearn_pnlss.gap.connections.locator.ConnectionLocator`):
   every place and force law fitted to the nominal's error by linear least
   squares, the force read off the measured motion; seconds;
2. refine (:func:`~sklearn_pnlss.gap.connections.refine.fit_connection`):
   the laws at the places that explain most, and a linear change at each,
   simulated to the periodic steady state and fitted by simulation error;
3. report (:meth:`StructuralGapDiagnosis.report`): the chosen connection and
   the nominal simulated on validation records, the gap each leaves, and
   what is left over the noise.
"""
from dataclasses import dataclass, replace
from numbers import Integral

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from ...physics.structure import Structure
from ...utils.parameters import Interval, Options, validates_parameters
from ...utils.threads import one_blas_thread
from ...utils.validation import as_signal_list
from ..modal_nominal import modal_nominal
from .entry import read_entry
from .locator import ConnectionLocator, band_and_weights
from .recalibrate import recalibrated
from .refine import BandError, fit_connection
from .spectra import free_lines
from .update import ElementUpdate, linear_corrections, updated_elements

__all__ = ["StructuralGapDiagnosis", "StructuralGapReport"]

#: A nonlinear law is claimed where its simulation leaves at most this share
#: of the squared training error a stiffness and damping change at the same
#: place leaves: less is a nominal's linear error that a nonlinear element
#: absorbs in part (measured on a linear chain: see the tests).
MAX_ERROR_RATIO = 0.7
#: A connection explains the gap fully where it leaves at most this much
#: over the noise (a factor of about three in rms).
EXPLAINED_DB = 10.0
#: The locator is run again around its leader's linear corrections, made
#: exactly, until they are below this (a log-factor: 1 % on a mass, a
#: spring, a frequency, a damping ratio or a shape's scale), at most this
#: many times: a nominal 10-30 % off is beyond a first-order correction.
CORRECTION_TOL, CORRECTION_ROUNDS = 0.01, 4
#: A round's step is halved this many times at most where it leaves more
#: error (a friction's first step overshot a spring by a factor 1.5).
STEP_HALVINGS = 2
#: The report names an updated element where its factor is this far from
#: one (a log-factor: 3 %).
UPDATE_SHOWN = 0.03
#: The records whose input is within this factor of the smallest one's rms
#: are the lowest level, where the nominal is recalibrated.
LOWEST_LEVEL = 1.1
#: The laws, by training error after their first fit, fitted again with the
#: nominal's linear corrections (elements or modes) free.
JOINT_FITS = 2


@dataclass(frozen=True)
class StructuralGapReport:
    """The diagnosis read on validation records.

    Attributes
    ----------
    effect_found : bool
        Whether a nonlinear connection explains the gap (see
        ``MAX_ERROR_RATIO``).
    place : tuple of (str, str or None)
        Where the chosen connection acts (the second point None: the ground).
    law : str
        Its force law.
    parameters : dict
        Its physical parameters.
    nominal_error, recalibrated_error, connection_error, linear_error : ndarray of shape (n_signals,)
        Each validation record's rms simulation error over its rms output in
        the band (outputs weighted by their noise): of the given nominal, of
        the recalibrated one, with the connection, and with a linear change
        at the same place instead.
    nominal_nrmse, connection_nrmse : ndarray of shape (n_signals, n_outputs)
        The same per output, unweighted.
    closure : ndarray of shape (n_signals,)
        Share of the given nominal's squared error that the recalibrated
        nominal with the connection removes.
    left_over_noise_db : ndarray of shape (n_signals,)
        What the connection leaves, in dB over the records' noise (0 dB:
        nothing but noise is left).
    ranking : list of ConnectionCandidate
        The locator's places, most explaining first.
    nominal_update : dict or None
        The factor on each of a lumped nominal's masses, springs and modal
        damping ratios that ``recalibrate`` fitted on the lowest training
        level (None: not updated so).
    entry : EntryReading or None
        Where the training records' content above the band enters (see
        :mod:`~sklearn_pnlss.gap.connections.entry`).
    """

    effect_found: bool
    place: tuple
    law: str
    parameters: dict
    nominal_error: np.ndarray
    recalibrated_error: np.ndarray
    connection_error: np.ndarray
    linear_error: np.ndarray
    nominal_nrmse: np.ndarray
    connection_nrmse: np.ndarray
    closure: np.ndarray
    left_over_noise_db: np.ndarray
    ranking: list
    nominal_update: dict = None
    entry: object = None

    @property
    def place_name(self):
        a, b = self.place
        return f"{a} and {'the ground' if b is None else b}"

    @property
    def fully_explained(self):
        """Whether the connection leaves no more than ``EXPLAINED_DB`` over
        the noise on every record: else something it does not hold is left
        (another law, another place, the nominal's own error)."""
        return bool(self.effect_found and np.all(self.left_over_noise_db <= EXPLAINED_DB))

    def __str__(self):
        head = (f"{self.law} between {self.place_name}" if self.effect_found else
                f"no nonlinear connection explains the gap (best tried: {self.law} between {self.place_name})")
        lines = [head + f", closing {np.mean(self.closure):.0%} of the nominal's squared error on the "
                 f"validation records on average"
                 + ("" if self.fully_explained or not self.effect_found else
                    f"; more than {EXPLAINED_DB:.0f} dB over the noise is left")]
        for i, (e0, er, e1, el, c, n) in enumerate(zip(self.nominal_error, self.recalibrated_error,
                                                       self.connection_error, self.linear_error, self.closure,
                                                       self.left_over_noise_db)):
            lines.append(f"  record {i}: error {e0:.3f} -> {e1:.3f} of the output (closes {c:.0%}; the "
                         f"recalibrated nominal: {er:.3f}, with a linear change there instead: {el:.3f}), "
                         f"{n:.0f} dB over the noise left")
        lines.append("  places by the share of the training error their force explains: " + ", ".join(
            f"{c.place_name} {c.explained:.0%}" for c in self.ranking))
        if self.entry is not None:
            lines.append("  " + str(self.entry))
        changed = {k: v for k, v in (self.nominal_update or {}).items() if abs(np.log(v)) >= UPDATE_SHOWN}
        if changed:
            lines.append("  the nominal updated on the lowest level first: " + ", ".join(
                f"{name} x{factor:.2f}" for name, factor in changed.items()))
        return "\n".join(lines)


class StructuralGapDiagnosis(BaseEstimator):
    """Diagnose the gap between a structure's simulator and measured
    periodic records: the place, the force law and how far it closes.

    The nominal's error is first read connection by connection
    (:class:`~sklearn_pnlss.gap.connections.locator.ConnectionLocator`,
    no simulation); at the ``n_places`` places whose force explains most
    (or, where the records carry content above the excited band clearly,
    at the place it enters: ``entry_``), every force law, and a linear
    stiffness and damping change, are then simulated and fitted by
    simulation error on the training records; the law that leaves the
    least error is the diagnosis when it beats the linear change clearly
    (``MAX_ERROR_RATIO``).

    Parameters
    ----------
    nominal : Structure or "modal"
        The linear simulator (e.g. :func:`~sklearn_pnlss.gap.modal_nominal`
        of the lowest level); "modal": a structure with only test data, its
        modes read off the training records themselves, at the lowest and
        at the highest level, whichever leaves the locator less to explain
        (a joint that sticks at low levels hides its own flexibility there:
        its modes show only once it slips; one sensor per point, of one
        kind, the single input at a sensed point).
    fs : float
        Sampling rate, Hz.
    period : int
        Samples per period of the records (one steady-state period or more
        each; of one, the noise is read at the lines the input leaves free).
    inputs : sequence of str
        Points of the input forces, one per column of ``X``.
    sensors : sequence of (str, str)
        ``(point, kind)`` of each column of ``y``.
    places, laws : sequence, default=None
        As :class:`ConnectionLocator` (None: all).
    f_band : (float, float), default=None
        Band of the error, Hz (None: the excited lines).
    n_places : int, default=2
        Places whose laws are simulated.
    oversampling : int, default=5
        Integration rate over the data rate.
    max_nfev : int, default=15
        Evaluations of each law's least squares at most.
    transient_periods : int, default=0
        Periods left out at the start of each record.
    recalibrate : bool, default=False
        Update the nominal on the best linear approximation of the lowest
        training level first: a lumped nominal's masses, springs and modal
        damping ratios (see :mod:`~sklearn_pnlss.gap.connections.update`; a
        model 10-30 % off), a modal one's in-band modes (frequency, damping
        ratio, shape scale; see
        :mod:`~sklearn_pnlss.gap.connections.recalibrate`).  Either way the
        elements or the modes are then corrected with every law, over every
        level, around the nominal, which is read again around the leader's
        corrections until they are small (``CORRECTION_TOL``).

    Attributes
    ----------
    reference_ : Structure
        The linear structure the diagnosis starts from: ``nominal``, or the
        modes read off the training record ``modal_record_``.
    modal_record_ : int or None
        With ``nominal="modal"``, the training record whose modes are the
        reference.
    nominal_ : Structure
        The nominal the connections are added to (the reference,
        recalibrated or as it is).
    locator_ : ConnectionLocator
    fits_ : list of ConnectionFit
        Every simulated law, least training error first.
    best_ : ConnectionFit
        The nonlinear law that leaves the least training error.
    entry_ : EntryReading
        Where the content above the band of the training records enters
        (:func:`~sklearn_pnlss.gap.connections.entry.read_entry`); where it
        names a place, the laws are simulated there only, else at the
        ``n_places`` places the locator ranks first.
    linear_ : dict
        The linear change fitted at each simulated place (a ConnectionFit).
    effect_found_ : bool
    updated_elements_ : dict or None
        The factors of a lumped nominal's update (see ``recalibrate``).
    nominal_train_error_, recalibrated_train_error_ : ndarray of shape (n_signals,)
        The given and the recalibrated nominal's training errors (rms over
        the rms output in the band, outputs weighted by their noise).

    Examples
    --------
    A dry friction between two masses of a chain, found from three
    accelerometers and two levels:

    >>> import numpy as np
    >>> from sklearn_pnlss.gap import StructuralGapDiagnosis
    >>> from sklearn_pnlss.physics import Connection, CoulombFriction, Structure
    >>> points = ["base", "middle", "tip"]
    >>> M, K = np.diag([3.0, 2.0, 1.0]), 5e4 * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    >>> C = 1e-4 * K + 0.5 * M
    >>> truth = Structure(M, C, K, points=points,
    ...                   connections=[Connection(CoulombFriction(2.0, 1e-3), "middle", "tip")])
    >>> sensors = [(p, "acceleration") for p in points]
    >>> rng = np.random.default_rng(0)
    >>> def records(levels):
    ...     X, Y = [], []
    ...     for level in levels:
    ...         spectrum = np.zeros(2049, complex)
    ...         spectrum[10:850:2] = np.exp(2j * np.pi * rng.random(420))
    ...         u = np.fft.irfft(spectrum)
    ...         u *= level / u.std()
    ...         a = truth.simulate(u, fs=200.0, inputs="base", sensors=sensors, periodic=True,
    ...                            oversampling=20, decimation=(4, 5))
    ...         X.append(np.tile(u, 2)[:, None])
    ...         Y.append(np.tile(a, (2, 1)) + 1e-3 * a.std(0) * rng.standard_normal((8192, 3)))
    ...     return X, Y
    >>> X, Y = records([10.0, 30.0])
    >>> gap = StructuralGapDiagnosis(Structure(M, C, K, points=points), fs=200.0, period=4096,
    ...                              inputs=["base"], sensors=sensors, n_places=1,
    ...                              laws=["cubic_stiffness", "coulomb_friction"]).fit(X, Y)
    >>> report = gap.report(*records([20.0]))
    >>> report.effect_found, report.place, report.law
    (True, ('middle', 'tip'), 'coulomb_friction')
    >>> gap.entry_.place  # read off the content above the band (41-100 Hz)
    ('middle', 'tip')
    >>> bool(report.closure[0] > 0.99), round(report.parameters["fc"], 1)
    (True, 2.0)
    """

    _parameter_constraints = {
        **{k: v for k, v in ConnectionLocator._parameter_constraints.items()
           if k not in ("linear_corrections", "participation", "motion_snr")},
        "nominal": [Structure, Options(str, {"modal"})],
        "n_places": [Interval(Integral, 1, None, closed="left")],
        "oversampling": [Interval(Integral, 1, None, closed="left")],
        "max_nfev": [Interval(Integral, 1, None, closed="left")],
        "recalibrate": ["boolean"],
    }

    def __init__(self, nominal, *, fs, period, inputs, sensors, places=None, laws=None, f_band=None, n_places=2,
                 oversampling=5, max_nfev=15, transient_periods=0, recalibrate=False):
        self.nominal = nominal
        self.fs = fs
        self.period = period
        self.inputs = inputs
        self.sensors = sensors
        self.places = places
        self.laws = laws
        self.f_band = f_band
        self.n_places = n_places
        self.oversampling = oversampling
        self.max_nfev = max_nfev
        self.transient_periods = transient_periods
        self.recalibrate = recalibrate

    @validates_parameters
    def fit(self, X, y):
        """Locate, then simulate and fit the laws at the leading places.

        Parameters
        ----------
        X : signals, (n_signals, n_samples, n_inputs) or a list
        y : signals, (n_signals, n_samples, n_sensors) or a list

        Returns
        -------
        self : StructuralGapDiagnosis
        """
        # BLAS on one thread throughout: the simulations run in threads of
        # their own, and the small solves between them (the optimiser's,
        # the shots') left BLAS's threads spinning against them (a friction
        # case: 86 s of wall time and 147 s of CPU, 68 s and 112 s)
        with one_blas_thread():
            return self._fit(X, y)

    def _fit(self, X, y):
        spectra = self._locator(None)._spectra(X, y)  # checked and read once for every round
        located = []
        for record, reference in self._references(X, y, spectra):
            nominal, updated = self._recalibrated(spectra, reference) if self.recalibrate else (reference, None)
            located.append((self._locator(nominal)._fit_spectra(spectra), reference, record, updated))
        # the reference whose best connection leaves the least error (the
        # same records, the same noise weights: comparable)
        self.locator_, self.reference_, self.modal_record_, self.updated_elements_ = min(
            located, key=lambda entry: entry[0].unexplained_)
        for _ in range(CORRECTION_ROUNDS - 1):
            corrections = self.locator_.best_.corrections
            if corrections is None or np.max(np.abs(corrections), initial=0.0) < CORRECTION_TOL:
                break
            # the corrections (of the elements or the modes) are
            # first-order: made exactly, the nominal is read again around
            # them (Gauss-Newton), a step kept only where it leaves less
            # error (a strong law's action, read in part as corrections,
            # made them overshoot and then diverge: their largest 0.05,
            # 0.2, then 1.3 in log-factor)
            again = self._stepped(spectra, corrections)
            if again is None:
                break
            self.locator_ = again
        self.nominal_ = self.locator_.nominal
        error = self._band_error(spectra)
        self.nominal_train_error_ = error.relative(error.simulate(self.reference_))
        self.recalibrated_train_error_ = error.relative(error.simulate(self.nominal_))
        places = list(dict.fromkeys(c.place for c in self.locator_.ranking_))[:self.n_places]
        band_top = spectra.freqs[self.locator_.lines_].max()
        self.entry_ = read_entry(spectra, self.sensors, band_top, self.locator_.places_)
        if self.entry_.clear:
            # the force's own points, read off the content above the band,
            # outrank the band's reading: in the band every place's motion
            # is a mix of the same few modes (see the module entry)
            places = [self.entry_.place]
        fits, self.linear_ = [], {}
        for place in places:
            scales = self.locator_.rms_[place]
            located = [self.locator_.linear_[place]] + [c for c in self.locator_.candidates_ if c.place == place]
            linear, *nonlinear = [fit_connection(self.locator_.nominal_for(c), c, error, scales=scales,
                                                 max_nfev=self.max_nfev) for c in located]
            self.linear_[place] = linear
            fits += nonlinear
        if not fits:  # the laws hold the linear change only
            fits = list(self.linear_.values())
        fits = sorted(fits, key=lambda f: np.mean(f.train_error**2))
        # the leaders and the linear changes at their places again, with the
        # nominal's corrections free too: the law's linear part and the
        # corrections trade against each other, and only a joint fit by
        # simulation settles them (a cubic spring otherwise lost to a
        # backlash by 2 % of the error, both 12 % of the output off)
        leaders = fits[:JOINT_FITS]
        if self.locator_.correction_ is not None:
            freqs = self.locator_.input_freqs_
            for i, f in enumerate(leaders):
                leaders[i] = self._joint(f, error, freqs)
            for place in dict.fromkeys(f.place for f in leaders):
                self.linear_[place] = self._joint(self.linear_[place], error, freqs)
        self.fits_ = sorted(leaders, key=lambda f: np.mean(f.train_error**2)) + fits[JOINT_FITS:]
        self.best_ = self.fits_[0]
        linear = self.linear_[self.best_.place]
        self.effect_found_ = bool(self.best_.law.element is not None and np.mean(self.best_.train_error**2)
                                  <= MAX_ERROR_RATIO * np.mean(linear.train_error**2))
        return self

    def _stepped(self, spectra, corrections):
        """The locator read again around its leader's corrections made, the
        step halved while it leaves more error than the locator now does
        (at most ``STEP_HALVINGS`` times); None where no step helps."""
        for k in range(STEP_HALVINGS + 1):
            nominal = self.locator_.correction_.applied(corrections / 2**k)
            made = self.locator_._made(corrections.size) + corrections / 2**k
            again = self._locator(nominal)._fit_spectra(spectra, made)
            if again.unexplained_ < self.locator_.unexplained_:
                return again
        return None

    def _joint(self, fit, error, freqs):
        """``fit`` refined again from where it ended, the linear corrections
        of its nominal free as well; kept where it lowers the error."""
        start = self.locator_.nominal_for(fit.candidate)
        located = replace(fit.candidate, parameters=dict(fit.parameters))
        correction = linear_corrections(start, freqs, inputs=self.inputs, sensors=self.sensors)
        joint = fit_connection(start, located, error, scales=self.locator_.rms_[fit.place], max_nfev=self.max_nfev,
                               correction=correction)
        if np.mean(joint.train_error**2) < np.mean(fit.train_error**2):
            return replace(joint, n_simulations=fit.n_simulations + joint.n_simulations,
                           seconds=fit.seconds + joint.seconds)
        return fit

    def _references(self, X, y, spectra):
        """``(record, structure)`` pairs the diagnosis may start from:
        ``(None, nominal)``, or with ``nominal="modal"`` the modes read off
        the lowest and the highest training record (by input rms; one that
        shows no mode a structure can have is left out)."""
        if not isinstance(self.nominal, str):
            return [(None, self.nominal)]
        points = [point for point, _ in self.sensors]
        kinds = {kind for _, kind in self.sensors}
        if len(set(points)) != len(points) or len(kinds) != 1 or len(self.inputs) != 1 \
                or self.inputs[0] not in points:
            raise ValueError("nominal='modal' reads the modes off one force at a sensed point, with one sensor per "
                             f"point, all of one kind; got inputs {list(self.inputs)} and sensors "
                             f"{list(self.sensors)}. Pass a Structure as nominal instead.")
        skip = self.transient_periods * self.period
        X_list = [u[skip:] for u in as_signal_list(X, name="X")[0]]
        y_list = [v[skip:] for v in as_signal_list(y, name="y")[0]]
        size = np.sqrt(np.mean(np.abs(spectra.U) ** 2, axis=(1, 2)))
        references, reasons = [], []
        for record in dict.fromkeys([int(np.argmin(size)), int(np.argmax(size))]):
            try:
                references.append((record, modal_nominal(X_list[record], y_list[record], fs=self.fs, points=points,
                                                         driving_point=self.inputs[0], kind=self.sensors[0][1],
                                                         period=self.period, f_band=self.f_band)))
            except ValueError as exc:
                reasons.append(f"record {record}: {exc}")
        if not references:
            raise ValueError("nominal='modal': no training record shows modes to start from (" + "; ".join(reasons)
                             + "). Pass a Structure as nominal.")
        return references

    def _recalibrated(self, spectra, nominal):
        """``nominal`` updated on the best linear approximation of the
        lowest training level, the records closest to linear: a lumped
        nominal's masses, springs and modal damping ratios (see
        :mod:`~sklearn_pnlss.gap.connections.update`), a modal one's in-band
        modes (see :mod:`~sklearn_pnlss.gap.connections.recalibrate`); and
        the lumped update's factors (None for a modal nominal)."""
        if spectra.U.shape[2] != 1:
            raise ValueError("recalibrate=True reads the frequency response of one input force; with "
                             f"{spectra.U.shape[2]} inputs pass recalibrate=False.")
        lines, weights = band_and_weights(spectra, self.f_band)
        U, Y = spectra.U[:, lines, 0], spectra.Y[:, lines]
        size = np.sqrt(np.mean(np.abs(U) ** 2, axis=1))
        lowest = size <= LOWEST_LEVEL * size.min()
        U, Y = U[lowest], Y[lowest]
        power = np.sum(np.abs(U) ** 2, axis=0)
        excited = power > 1e-6 * power.max()
        frf = np.sum(Y[:, excited] * U[:, excited, None].conj(), axis=0) / power[excited, None]
        freqs = spectra.freqs[lines][excited]
        if ElementUpdate.of(nominal) is not None:
            return updated_elements(nominal, freqs, frf[:, :, None], weights, fs=self.fs, inputs=self.inputs,
                                    sensors=self.sensors)
        return recalibrated(nominal, freqs, frf[:, :, None], weights, inputs=self.inputs, sensors=self.sensors), None

    def _locator(self, nominal):
        return ConnectionLocator(nominal, fs=self.fs, period=self.period, inputs=self.inputs, sensors=self.sensors,
                                 places=self.places, laws=self.laws, f_band=self.f_band,
                                 transient_periods=self.transient_periods)

    def _band_error(self, spectra):
        return BandError(spectra, self.locator_.lines_, self.locator_.output_weights_, self.inputs, self.sensors,
                         self.oversampling)

    def report(self, X, y):
        """The diagnosis on validation records.

        Parameters
        ----------
        X, y : signals
            Periodic records, as in :meth:`fit`.

        Returns
        -------
        StructuralGapReport
        """
        check_is_fitted(self, "best_")
        error = self._band_error(self.locator_._spectra(X, y))
        with one_blas_thread():  # as in fit
            nominal, recalibrated, connection, linear = (_simulated(error, s) for s in (
                self.reference_, self.nominal_, self.best_.structure, self.linear_[self.best_.place].structure))
        e0, e1 = error.relative(nominal), error.relative(connection)
        left = np.sum(np.abs(connection - error.measured) ** 2, axis=(1, 2))
        noise = _noise_power(error, connection)
        return StructuralGapReport(
            effect_found=self.effect_found_, place=self.best_.place, law=self.best_.law.name,
            parameters=dict(self.best_.parameters), nominal_error=e0,
            recalibrated_error=error.relative(recalibrated), connection_error=e1,
            linear_error=error.relative(linear), nominal_nrmse=_per_output(nominal, error.measured),
            connection_nrmse=_per_output(connection, error.measured), closure=1.0 - e1**2 / e0**2,
            left_over_noise_db=10 * np.log10(left / noise), ranking=list(self.locator_.ranking_),
            nominal_update=self.updated_elements_, entry=self.entry_)


def _simulated(error, structure):
    """The structure's weighted band spectra on the records, infinite where
    its simulation diverges (a fitted model must not pass for a good one)."""
    try:
        return error.simulate(structure)
    except (FloatingPointError, ValueError, np.linalg.LinAlgError):
        return np.full(error.measured.shape, np.inf + 0j)


def _noise_power(error, simulated):
    """Each record's weighted noise power summed over the band's lines: from
    the spread of its periods, or for a record of one period from what
    ``simulated`` leaves at the band's lines the input leaves free (the
    measured output there holds the nonlinearity's content as well; a
    model that captures it leaves the noise alone, an upper bound)."""
    noise = np.sum(error.spectra.Y_noise[:, error.lines] * error.weights**2, axis=(1, 2))
    for i in np.flatnonzero(error.spectra.n_periods == 1):
        free = free_lines(error.spectra.U[i])[error.lines]
        if free.any():
            noise[i] = error.lines.size * np.sum(np.mean(np.abs(simulated[i, free] - error.measured[i, free]) ** 2,
                                                         axis=0))
    return noise


def _per_output(simulated, measured):
    """Rms error over rms output at the band's lines, per record and output
    (weights cancel)."""
    return np.sqrt(np.sum(np.abs(simulated - measured) ** 2, axis=1) / np.sum(np.abs(measured) ** 2, axis=1))
