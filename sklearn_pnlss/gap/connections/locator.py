"""Where in a structure the simulator is wrong: the connection whose force,
on the measured motion, explains the nominal's error.

The equation of motion of the real structure is the nominal's plus the
forces it misses.  A force ``f`` acting on the relative motion of two points
``a`` and ``b`` (``+f`` at ``a``, ``-f`` at ``b``; ``b`` may be the ground)
changes every sensor's spectrum by ``-H_c(w) F(w)``, ``H_c`` the nominal's
response to that pair of forces.  So, line by line,

    Y(w) - H(w) U(w) = -H_c(w) F[f(d_ab, v_ab)](w),

the left side the nominal's error on the measured records, ``d_ab`` and
``v_ab`` the relative displacement and velocity of the two points, which
the sensors at both points measure (nonlinear identification through
feedback of the outputs, Adams and Allemang 2000).  A force law linear in
its coefficients (:mod:`~sklearn_pnlss.gap.connections.laws`) makes this a
linear least-squares problem for every place and law: all candidates in
seconds, with no simulation, on every training record at once, so that a
law has to hold from level to level.

Three readings make the measured motion fit for this:

- only lines where the relative motion stands above its noise are kept
  (``MOTION_SNR``): its double integration amplifies the noise at low
  frequencies, and a noisy regressor biases every coefficient;
- the nonlinear force is evaluated at ``ALIAS_FACTOR`` times the data rate
  (zero-padded spectra): a cubic of a band-limited motion has three times
  its bandwidth, which folds back into the band at the data rate;
- each output is weighted by its own noise, so that an accelerometer with
  large readings does not outvote the others.

A nominal read off measurements knows a connection's share of each mode,
``phi_a - phi_b``, only as the difference of two shapes read at one
driving point: small and uncertain where the two points move almost
together, as the two sides of a stiff joint do.  ``participation="free"``
fits that share too, one coefficient per mode and regressor (the law's
coefficients times the connection's share of each mode, without the
factorisation): the place is then judged by how well its measured relative
motion explains the error, not by the nominal's shapes there.
"""
from dataclasses import dataclass, field, replace
from itertools import combinations
from numbers import Integral, Real

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from ...physics.structure import SENSOR_KINDS, Structure
from ...utils.parameters import Interval, Options, validates_parameters
from .laws import LAW_NAMES, force_laws
from .update import linear_corrections
from .spectra import PeriodSpectra

__all__ = ["ConnectionLocator", "ConnectionCandidate", "band_and_weights"]

#: A line of the relative motion is used where its power is this many times
#: its noise variance (20 dB): below it the double integration hands the
#: regressors more noise than motion, which biases every coefficient (a
#: chain's cubic spring with 0.1 % sensor noise: at 10 dB the wrong pair of
#: masses explained most, at 20, 30 and 40 dB the right one 99.9 % with
#: k3 within 1 %).
MOTION_SNR = 100.0
#: What a linear correction of one (a factor e on a mass, a spring, a
#: frequency, a damping ratio or a shape's scale), counted from the nominal
#: given, costs in the fit, as a share of the records' output energy: a
#: correction of 10 % costs a thousandth, nothing next to one the records
#: determine; one that only absorbs a law's action is held back (a friction
#: that nearly locks its joint had walked an exact chain's springs by
#: factors up to 500 over four rounds, and no fit came back from there).
CORRECTION_PRICE = 0.1
#: Noise variance an output is credited with at least, relative to its
#: power in the band (noise-free simulated records).
NOISE_FLOOR = 1e-12
#: The nonlinear forces are evaluated at this multiple of the data rate.
ALIAS_FACTOR = 8


@dataclass(frozen=True)
class ConnectionCandidate:
    """A force law at a place, fitted to the nominal's error.

    Attributes
    ----------
    place : tuple of (str, str or None)
        The two points (the second None: the ground).
    law : ForceLaw
    coefficients : ndarray
        The law's coefficients (see :attr:`ForceLaw.param_names`).
    parameters : dict
        Physical parameters: the stiffness (N/m) and damping (N s/m) changes
        at the connection, the element's coefficient and fixed parameters.
    explained : float
        Share of the nominal's (noise-weighted) squared error on the
        training records that the connection's force explains.
    linear_explained : float
        The share a stiffness and damping change at the same place explains.
    corrections : ndarray or None
        The nominal's linear corrections fitted with the law (see
        ``linear_corrections``).
    participation : ndarray or None
        With ``participation="free"``: the connection's fitted share of each
        degree of freedom it acts on, in units of the nominal's own
        (``Structure.direction``); ``coefficients`` then holds one per
        degree of freedom and regressor, and ``parameters`` the law's
        coefficients of their best rank-one split. None: the nominal's.
    """

    place: tuple
    law: object
    coefficients: np.ndarray
    parameters: dict
    explained: float
    linear_explained: float = None
    corrections: np.ndarray = None
    participation: np.ndarray = None

    @property
    def nonlinear_gain(self):
        """What the law explains beyond a linear change at its place: the
        share a nonlinear element is credited with (a nominal read at
        another level, or integrated at another rate, leaves a linear error
        that a linear change there partly explains)."""
        return self.explained - (self.explained if self.linear_explained is None else self.linear_explained)

    @property
    def place_name(self):
        a, b = self.place
        return f"{a} - {'ground' if b is None else b}"

    def __repr__(self):
        return f"<{self.law.name} between {self.place_name}: explains {self.explained:.1%}>"


@dataclass
class _PlaceData:
    """What one place's fits need on a set of records."""

    response: np.ndarray  # H_c: (n_lines, n_outputs)
    displacement: list = field(default_factory=list)  # per record, at ALIAS_FACTOR x the rate
    velocity: list = field(default_factory=list)


def band_and_weights(spectra, f_band):
    """The lines of the band (``f_band``, Hz, or the excited lines' span)
    and each output's weight, the inverse rms of its noise there."""
    freqs = spectra.freqs
    if f_band is None:
        power = np.sum(np.abs(spectra.U) ** 2, axis=(0, 2))
        excited = np.flatnonzero(power > 1e-6 * power.max())
        excited = excited[excited > 0]
        lo, hi = freqs[excited.min()], freqs[excited.max()]
    else:
        lo, hi = f_band
    lines = np.flatnonzero((freqs >= lo) & (freqs <= hi) & (freqs > 0))
    if lines.size < 4:
        raise ValueError(f"f_band={f_band!r} holds {lines.size} lines of the spectrum; widen it.")
    noise = spectra.Y_noise[:, lines].mean(axis=(0, 1))
    power = np.mean(np.abs(spectra.Y[:, lines]) ** 2, axis=(0, 1))
    # noise-free records (a simulation) weigh outputs by their size
    return lines, 1.0 / np.sqrt(np.maximum(noise, NOISE_FLOOR * power))


class ConnectionLocator(BaseEstimator):
    """Find the connection of a structure whose missing force explains the
    simulator's error on measured periodic records.

    Every place (a pair of sensed points, or a sensed point and the
    ground) is tried with every force law; each is fitted by linear least
    squares on the nominal's error in the frequency domain, the force being
    evaluated on the measured relative motion (see the module's notes).  No
    simulation is run: a structural test's dozens of candidates take
    seconds.  What it gives is a ranking by the share of the error each
    connection explains; a simulation of the chosen connection then tells
    how far the gap closes.

    Parameters
    ----------
    nominal : Structure
        The linear simulator (its connections are left out).
    fs : float
        Sampling rate, Hz.
    period : int
        Samples per period: every record is a whole number of steady-state
        periods (their spread is the noise; a record of one period has its
        noise read at the lines the input leaves free, see
        :mod:`~sklearn_pnlss.gap.connections.spectra`).
    inputs : sequence of str
        The points the input forces act on, one per column of ``X``.
    sensors : sequence of (str, str)
        ``(point, kind)`` of each column of ``y``, ``kind`` one of
        ``"displacement"``, ``"velocity"``, ``"acceleration"``.
    places : sequence of (str, str or None), default=None
        The places tried; None: every pair of sensed points and every
        sensed point to the ground.
    laws : sequence of str, default=None
        Force laws from :data:`~sklearn_pnlss.gap.connections.laws.LAW_NAMES`;
        None: all of them.
    f_band : (float, float), default=None
        Band where the nominal is trusted and the error is read, Hz; None:
        the lines the input excites.
    transient_periods : int, default=0
        Periods at the start of each record left out.
    linear_corrections : bool, default=True
        Fit small changes of the nominal (the same at every level) with
        every law: the nominal's own linear error, which a law fitted alone
        absorbs in part.  A lumped nominal's are its elements' (masses,
        springs, modal damping ratios:
        :class:`~sklearn_pnlss.gap.connections.update.ElementCorrection`),
        a modal one's its in-band modes' (frequency, damping ratio, shape
        scale:
        :class:`~sklearn_pnlss.gap.connections.recalibrate.ModalCorrection`).
        Not with ``participation="free"``, whose linear law already changes
        every mode's stiffness and damping on its own.
    participation : {"nominal", "free"}, default="nominal"
        A connection's share of each degree of freedom (each coupled mode
        of a modal nominal, each mass of a lumped one): the nominal's
        ``phi_a - phi_b``, or fitted with the law (see the module's notes).
    motion_snr : float, default=MOTION_SNR
        Power ratio over its noise at which a line of a relative motion is
        used (100: 20 dB).

    Attributes
    ----------
    ranking_ : list of ConnectionCandidate
        Every place's best nonlinear law (its linear one when ``laws`` has
        none), most explaining first.
    candidates_ : list of ConnectionCandidate
        Every place's every nonlinear law (a backlash at its best
        clearance), most explaining first.
    linear_ : dict
        Each place's linear law (a stiffness and damping change there),
        fitted whatever ``laws`` holds: the nonlinear laws are judged
        against it (:attr:`ConnectionCandidate.nonlinear_gain`).
    best_ : ConnectionCandidate
        ``ranking_[0]``.
    nominal_error_ : ndarray of shape (n_signals,)
        The nominal's rms error over the rms output in the band, per
        training record (outputs weighted by their noise).
    unexplained_ : float
        The weighted error energy ``best_`` leaves, summed over the records,
        with its corrections' prior cost (``CORRECTION_PRICE``): comparable
        between nominals, where ``explained`` is a share of each one's own
        error.
    made_corrections_ : ndarray or None
        The linear corrections a diagnosis made to reach ``nominal`` from
        the one it was given, which the prior counts (None: none).

    Examples
    --------
    Three masses in a chain, a cubic spring between the middle one and the
    tip, accelerometers on all three, two levels of a periodic multisine:

    >>> import numpy as np
    >>> from sklearn_pnlss.gap import ConnectionLocator
    >>> from sklearn_pnlss.physics import Connection, CubicStiffness, Structure
    >>> points = ["base", "middle", "tip"]
    >>> M, K = np.diag([3.0, 2.0, 1.0]), 5e4 * np.array([[2.0, -1, 0], [-1, 2, -1], [0, -1, 1]])
    >>> C = 1e-4 * K + 0.5 * M
    >>> truth = Structure(M, C, K, points=points,
    ...                   connections=[Connection(CubicStiffness(3e8), "middle", "tip")])
    >>> sensors = [(p, "acceleration") for p in points]
    >>> rng = np.random.default_rng(0)
    >>> spectrum = np.zeros(2049, complex)
    >>> spectrum[10:850:2] = np.exp(2j * np.pi * rng.random(420))
    >>> u = np.fft.irfft(spectrum)
    >>> X, Y = [], []
    >>> for level in (20.0, 60.0):
    ...     a = truth.simulate(level * u / u.std(), fs=200.0, inputs="base", sensors=sensors,
    ...                        periodic=True, oversampling=20, decimation=(4, 5))
    ...     X.append(np.tile(level * u / u.std(), 2)[:, None])
    ...     Y.append(np.tile(a, (2, 1)) * (1 + 1e-3 * rng.standard_normal((8192, 3))))
    >>> loc = ConnectionLocator(Structure(M, C, K, points=points), fs=200.0, period=4096,
    ...                         inputs=["base"], sensors=sensors).fit(X, Y)
    >>> loc.best_.place, loc.best_.law.name
    (('middle', 'tip'), 'cubic_stiffness')
    >>> bool(abs(loc.best_.parameters["k3"] / 3e8 - 1) < 0.05)
    True
    """

    _parameter_constraints = {
        "nominal": [Structure],
        "fs": [Interval(Real, 0, None, closed="neither")],
        "period": [Interval(Integral, 16, None, closed="left")],
        "inputs": [list, tuple],
        "sensors": [list, tuple],
        "places": [list, tuple, None],
        "laws": [list, tuple, None],
        "f_band": [tuple, list, None],
        "transient_periods": [Interval(Integral, 0, None, closed="left")],
        "linear_corrections": ["boolean"],
        "participation": [Options(str, {"nominal", "free"})],
        "motion_snr": [Interval(Real, 0, None, closed="left")],
    }

    def __init__(self, nominal, *, fs, period, inputs, sensors, places=None, laws=None, f_band=None,
                 transient_periods=0, linear_corrections=True, participation="nominal", motion_snr=MOTION_SNR):
        self.nominal = nominal
        self.fs = fs
        self.period = period
        self.inputs = inputs
        self.sensors = sensors
        self.places = places
        self.laws = laws
        self.f_band = f_band
        self.transient_periods = transient_periods
        self.linear_corrections = linear_corrections
        self.participation = participation
        self.motion_snr = motion_snr

    # -- fitting ------------------------------------------------------------
    @validates_parameters
    def fit(self, X, y):
        """Fit every force law at every place to the nominal's error.

        Parameters
        ----------
        X : signals, (n_signals, n_samples, n_inputs) or a list
            Measured forces at ``inputs``.
        y : signals, (n_signals, n_samples, n_sensors) or a list
            Measured responses of ``sensors``.

        Returns
        -------
        self : ConnectionLocator
        """
        return self._fit_spectra(self._spectra(X, y))

    def _fit_spectra(self, spectra, made=None):
        """:meth:`fit` on the records' checked spectra (a diagnosis reads
        them once for all its rounds); ``made``: the linear corrections
        already made to reach this nominal, which the prior counts."""
        self.made_corrections_ = made
        self.lines_, self.output_weights_ = band_and_weights(spectra, self.f_band)
        freqs = spectra.freqs[self.lines_]
        self.input_response_ = self.nominal.frequency_response(freqs, inputs=list(self.inputs),
                                                               sensors=list(self.sensors))
        self.input_freqs_ = freqs
        self.correction_ = (linear_corrections(self.nominal, freqs, inputs=self.inputs, sensors=self.sensors)
                            if self.linear_corrections and self.participation == "nominal" else None)
        error = self._weighted_error(spectra)
        output_energy = np.sum(np.abs(spectra.Y[:, self.lines_] * self.output_weights_) ** 2, axis=(1, 2))
        self._prior_weight = np.sqrt(CORRECTION_PRICE * np.sum(output_energy))
        self.nominal_error_ = np.sqrt(np.sum(np.abs(error) ** 2, axis=(1, 2)) / output_energy)
        self.places_ = self._places()
        self.rms_ = {}
        ranking, self.linear_, self.candidates_ = [], {}, []
        corrections = None
        if self.correction_ is not None and self.correction_.n_params:
            corrections = [self._correction_columns(spectra, i) for i in range(error.shape[0])]
        for place in self.places_:
            data = self._place_data(place, spectra, freqs)
            d_rms = np.sqrt(np.mean(np.concatenate(data.displacement) ** 2))
            v_rms = np.sqrt(np.mean(np.concatenate(data.velocity) ** 2))
            self.rms_[place] = (d_rms, v_rms)
            linear = self.linear_[place] = self._fit_law(force_laws(["linear"], d_rms, v_rms)[0], place, data,
                                                         error, corrections)
            fits = [replace(self._fit_law(law, place, data, error, corrections), linear_explained=linear.explained)
                    for law in force_laws(self.laws or LAW_NAMES, d_rms, v_rms) if law.element is not None]
            ranking.append(max(fits, key=lambda c: c.explained) if fits else linear)
            for name in dict.fromkeys(c.law.name for c in fits):  # a backlash's best clearance
                self.candidates_.append(max((c for c in fits if c.law.name == name), key=lambda c: c.explained))
        self.ranking_ = sorted(ranking, key=lambda c: -c.explained)
        self.candidates_.sort(key=lambda c: -c.explained)
        self.best_ = self.ranking_[0]
        # what the best leaves, its corrections' prior cost with it: a round
        # of corrections is judged by both
        self.unexplained_ = float((1.0 - self.best_.explained) * np.sum(np.abs(error) ** 2))
        if self.best_.corrections is not None:
            self.unexplained_ += float(np.sum((self._prior_weight * (self._made(self.best_.corrections.size)
                                                                     + self.best_.corrections)) ** 2))
        return self

    def _spectra(self, X, y):
        spectra = PeriodSpectra.from_signals(X, y, period=self.period, fs=self.fs,
                                             transient_periods=self.transient_periods)
        if spectra.U.shape[2] != len(self.inputs):
            raise ValueError(f"X has {spectra.U.shape[2]} input channel(s) but inputs names "
                             f"{len(self.inputs)} point(s): one point per column of X.")
        if spectra.Y.shape[2] != len(self.sensors):
            raise ValueError(f"y has {spectra.Y.shape[2]} channel(s) but sensors names {len(self.sensors)}: "
                             "one (point, kind) per column of y.")
        return spectra

    def _places(self):
        sensed = list(dict.fromkeys(point for point, _ in self.sensors))
        if self.places is None:
            return [*combinations(sensed, 2), *((p, None) for p in sensed)]
        places = []
        for i, place in enumerate(self.places):
            a, b = (tuple(place) + (None,))[:2]
            for p in (a, b):
                if p is not None and p not in sensed:
                    raise ValueError(f"places[{i}] names {p!r}, which no sensor measures; a connection's "
                                     f"relative motion must be measured at both its points ({sensed}).")
            places.append((a, b))
        return places

    def _weighted_error(self, spectra):
        """The nominal's error at the band's lines, outputs weighted by
        their noise: (n_signals, n_lines, n_outputs)."""
        Y = spectra.Y[:, self.lines_]
        predicted = np.einsum("los,nls->nlo", self.input_response_, spectra.U[:, self.lines_])
        return (Y - predicted) * self.output_weights_

    def _motion(self, point, spectra):
        """The measured displacement spectra of ``point`` and their noise
        variance, from its first sensor (zero at DC: an offset is
        unknown)."""
        j = next(i for i, (p, _) in enumerate(self.sensors) if p == point)
        power = SENSOR_KINDS.index(self.sensors[j][1])
        s = 2j * np.pi * spectra.freqs
        s[0] = 1.0
        D = spectra.Y[:, :, j] / s**power
        noise = spectra.Y_noise[:, :, j] / np.abs(s) ** (2 * power)
        D[:, 0] = 0.0
        return D, noise

    def _place_data(self, place, spectra, freqs):
        a, b = place
        data = _PlaceData(self.nominal.connection_response(freqs, a, b, sensors=list(self.sensors))
                          if self.participation == "nominal" else
                          self.nominal.dof_response(freqs, sensors=list(self.sensors)))
        D, noise = self._motion(a, spectra)
        if b is not None:
            D_b, noise_b = self._motion(b, spectra)
            D, noise = D - D_b, noise + noise_b
        D = np.where(np.abs(D) ** 2 > self.motion_snr * noise, D, 0.0)
        s = 2j * np.pi * spectra.freqs
        n_fine = ALIAS_FACTOR * self.period
        for Dk in D:
            data.displacement.append(np.fft.irfft(Dk, n_fine) * ALIAS_FACTOR)
            data.velocity.append(np.fft.irfft(s * Dk, n_fine) * ALIAS_FACTOR)
        return data

    def _columns(self, law, data, index):
        """The design columns of record ``index``: each regressor's force
        through the place's response (each degree of freedom's, with a free
        participation), weighted like the error (n_lines * n_outputs,
        n_coefficients), complex."""
        forces = law.regressors(data.displacement[index], data.velocity[index])
        F = np.fft.rfft(forces, axis=0)[self.lines_] / ALIAS_FACTOR
        response = data.response[:, :, None] if data.response.ndim == 2 else data.response
        cols = -response[:, :, :, None] * F[:, None, None, :] * self.output_weights_[None, :, None, None]
        return cols.reshape(cols.shape[0] * cols.shape[1], -1)

    def _correction_columns(self, spectra, index):
        """The linear corrections' design columns of record ``index``,
        weighted like the error (n_lines * n_outputs, n_params)."""
        cols = self.correction_.columns(spectra.U[index, self.lines_]) * self.output_weights_[None, :, None]
        return cols.reshape(-1, self.correction_.n_params)

    def _fit_law(self, law, place, data, error, corrections):
        """The law's coefficients, and the linear corrections with them (the
        columns ``corrections`` of each record, or None)."""
        n = error.shape[0]
        A = np.concatenate([self._columns(law, data, i) if corrections is None else
                            np.hstack([self._columns(law, data, i), corrections[i]]) for i in range(n)])
        b = error.reshape(-1)
        A2, b2 = np.concatenate([A.real, A.imag]), np.concatenate([b.real, b.imag])
        n_law = len(law.param_names) * (1 if data.response.ndim == 2 else data.response.shape[2])
        # the prior: each correction, with those already made, costs
        # CORRECTION_PRICE of the output's energy per unit
        prior = np.zeros((A2.shape[1] - n_law, A2.shape[1]))
        prior[:, n_law:] = self._prior_weight * np.eye(prior.shape[0])
        A_fit, b_fit = np.vstack([A2, prior]), np.concatenate([b2, -self._prior_weight * self._made(prior.shape[0])])
        scale = np.linalg.norm(A_fit, axis=0)
        scale[scale == 0] = 1.0
        coef = np.linalg.lstsq(A_fit / scale, b_fit, rcond=None)[0] / scale
        k = law.param_names.index(law.coefficient) if law.coefficient in law.nonnegative else None
        if data.response.ndim == 2 and k is not None and coef[k] < 0:
            # a coefficient that must not be negative (a passive element)
            # is held at zero: the law adds nothing to its linear part
            A_fit[:, k], scale[k] = 0.0, 1.0
            coef = np.linalg.lstsq(A_fit / scale, b_fit, rcond=None)[0] / scale
            coef[k] = 0.0  # exactly (its column's least-norm value is a rounding error's)
        explained = 1.0 - np.sum((b2 - A2 @ coef) ** 2) / np.sum(b2**2)
        law_coef, participation = coef[:n_law], None
        if data.response.ndim == 3:
            participation, law_coef = self._split(place, law_coef.reshape(-1, len(law.param_names)))
        return ConnectionCandidate(place, law, coef[:n_law], law.parameters(law_coef), float(explained),
                                   corrections=None if corrections is None else coef[n_law:],
                                   participation=participation)

    def _split(self, place, coefficients):
        """A free participation's coefficients (n_dof, n_regressors) split
        into the connection's share of each degree of freedom and the law's
        coefficients, by their best rank-one approximation, the share scaled
        to the nominal's own in least squares (its sign and size are
        otherwise the law's)."""
        u, sv, vt = np.linalg.svd(coefficients, full_matrices=False)
        share, law = u[:, 0] * sv[0], vt[0]
        own = self.nominal.direction(*place)[self.nominal.coupled]
        scale = float(share @ own) / max(float(own @ own), 1e-300)
        if scale == 0.0:
            return share, law
        return share / scale, law * scale

    def _made(self, n):
        """The corrections already made to reach the nominal (none: the
        nominal as given)."""
        return np.zeros(n) if self.made_corrections_ is None else self.made_corrections_

    def nominal_for(self, candidate):
        """The nominal with a candidate's linear corrections made (the
        nominal itself without them)."""
        if candidate.corrections is None or self.correction_ is None:
            return self.nominal
        return self.correction_.applied(candidate.corrections)

    # -- reading new records -------------------------------------------------
    def _energies(self, X, y, candidate):
        """Per record: the nominal's squared (weighted) error, what is left
        of it once the candidate's force is added, and the output's."""
        check_is_fitted(self, "best_")
        candidate = self.best_ if candidate is None else candidate
        spectra = self._spectra(X, y)
        data = self._place_data(candidate.place, spectra, spectra.freqs[self.lines_])
        error = self._weighted_error(spectra)
        nominal, left = [], []
        for i, e in enumerate(error.reshape(error.shape[0], -1)):
            nominal.append(np.sum(np.abs(e) ** 2))
            e = e - self._columns(candidate.law, data, i) @ candidate.coefficients
            if candidate.corrections is not None:
                e = e - self._correction_columns(spectra, i) @ candidate.corrections
            left.append(np.sum(np.abs(e) ** 2))
        size = np.sum(np.abs(spectra.Y[:, self.lines_] * self.output_weights_) ** 2, axis=(1, 2))
        return np.array(nominal), np.array(left), size

    def explained(self, X, y, candidate=None):
        """Share of the nominal's error on each of these records that a
        fitted candidate's force explains, its coefficients fixed.

        Parameters
        ----------
        X, y : signals
            Periodic records, as in :meth:`fit` (validation levels).
        candidate : ConnectionCandidate, default=None
            One of ``ranking_`` or ``linear_``'s values; None: ``best_``.

        Returns
        -------
        nominal_error : ndarray of shape (n_signals,)
            The nominal's rms error over the rms output in the band.
        explained : ndarray of shape (n_signals,)
            The share of the squared error the candidate's force removes
            (negative where it adds error).
        """
        nominal, left, size = self._energies(X, y, candidate)
        return np.sqrt(nominal / size), 1.0 - left / nominal

    def score(self, X, y):
        """Share of the nominal's squared error on these records, all
        together, that the best connection's force explains (1: all of it,
        0: none, negative: it adds error)."""
        nominal, left, _ = self._energies(X, y, None)
        return float(1.0 - np.sum(left) / np.sum(nominal))
