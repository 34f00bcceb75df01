"""Noise floor of the measurements and the test of whether a gap is real.

The noise is best read from what changes from one period to the next of a
steady-state periodic measurement; its spectrum gives both the floor that no
model can go below and the effective number of independent samples, which
the test of a gap against that floor needs (band-limited noise has far fewer
than one per sample).

Lab data often repeat no period (one period per realisation, multisine
realisations separated by zero-input gaps, filtered noise, a ramp).  The
floor then comes from what those data do give, in this order:

``"periods"``
    the spread over the periods of the training signals of two periods or
    more (exact: the structure repeats, only noise changes);
``"repeated_inputs"``
    the difference between training signals driven by the same input
    (exact as well, when the user ran a realisation twice);
``"non_excited_lines"``
    the residual of the best-fitting model (the nominal, a fitted
    candidate, the black box) at the DFT lines the input does not excite:
    there the model's response is nearly zero, so its residual is the noise
    plus whatever nonlinear distortion that model leaves unexplained.  An
    upper bound, close to the noise once one model captures the effect;
``"black_box_residual"``
    the last resort, when the inputs excite every line: the black box's
    validation residual (see :func:`residual_noise`).

Each :class:`NoiseFloor` says which of these set it (``source``, and a
sentence in ``detail``), and the report prints it with the verdict.
"""
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ...frequency.noise import periodic_noise_variance
from ...utils.validation import is_periodic
from ..settings import SETTINGS

__all__ = ["NoiseFloor", "drift_free_variance", "estimate_noise", "unsettled_signals", "repeated_input_noise",
           "non_excited_noise", "residual_noise", "gap_test", "banded_spectrum",
           "free_of_input"]

#: Frequency bands over which a noise level read at scattered DFT lines is
#: averaged (then interpolated, in dB, over the lines it was not read at).
N_NOISE_BANDS = 16
#: DFT lines a band needs to give a level of its own (a chi-square of 32
#: degrees of freedom: the level to within about 1 dB).
MIN_LINES_PER_BAND = 16
#: Length (samples) of the Hann-windowed segments a record that is not
#: periodic is read in when one window over the whole record leaves no band
#: with enough lines free of input: a jump inside the record (two
#: realisations joined) leaks over every line of a window that holds it, and
#: read in segments only the segments holding a jump lose their lines.
#: Segments are the fallback, not the rule: in a quiet stretch (a zero-input
#: gap) the response still rings from the input before it, and their many
#: lines near the band carry the harmonics a wrong model leaves, which raised
#: the floor 20 dB above the noise when no candidate held the effect.
NOISE_SEGMENT = 4096


@dataclass
class NoiseFloor:
    """Output noise of the training signals.

    Attributes
    ----------
    variance : float
        Noise variance per sample, m^2.
    spectrum : ndarray of shape (n_grid // 2 + 1,)
        Noise variance of the unitary DFT of an ``n_grid``-sample record per
        bin, m^2 (``n_grid`` is the period when there is one).
    dof_per_sample : float
        Independent real samples per time sample (1 for white noise, about
        the occupied fraction of the band otherwise).
    source : str, default="periods"
        Which estimate this is: ``"periods"``, ``"repeated_inputs"``,
        ``"non_excited_lines"`` or ``"black_box_residual"`` (see the module
        docstring).
    detail : str, default=""
        What the estimate was read from, in a sentence for the report.
    upper_bound : bool, default=False
        True when the estimate may hold more than noise (a model's residual).
    """

    variance: float
    spectrum: np.ndarray
    dof_per_sample: float
    source: str = "periods"
    detail: str = ""
    upper_bound: bool = False

    @property
    def rms(self):
        return float(np.sqrt(self.variance))

    @property
    def replicated(self):
        """Whether the floor comes from the data repeating themselves
        (periods, repeated inputs) rather than from a model's residual."""
        return self.source in ("periods", "repeated_inputs")


def drift_free_variance(y_list, period):
    """Noise variance of one period's unitary DFT per bin, from what changes
    between periods once a slow trend over the periods is removed.

    A structure that drifts (stiffness changing with temperature) changes
    its response from period to period too; taken as noise, that change
    would raise the floor up to the gap itself and hide it.  So each bin is
    regressed on a polynomial in the period index, of degree two with four
    periods or more, one with three, and the residual spread is the noise
    (``P - 3``, ``P - 2`` degrees of freedom); two periods give their plain
    spread (one).  A strong drift is not a polynomial of the period index
    (near a resonance the response is far from linear in the stiffness), so
    the result is then an upper bound.  None without a signal of two
    periods.
    """
    var = periodic_noise_variance([np.asarray(y, dtype=float).reshape(-1, 1) for y in y_list], period,
                                  trend_degree=2)
    return None if var is None else var[:, 0]


def _from_spectrum(spectrum, n_grid, **kwargs):
    """:class:`NoiseFloor` of a per-bin unitary-DFT noise variance."""
    # Two-sided spectrum: the bins between DC and Nyquist count twice.
    weights = np.full(spectrum.size, 2.0)
    weights[0] = 1.0
    if n_grid % 2 == 0:
        weights[-1] = 1.0
    total = np.sum(weights * spectrum)
    # Satterthwaite: a sum of independent variance terms has the degrees of
    # freedom of (sum s)^2 / sum s^2, each complex bin carrying two.
    dof = total**2 / np.sum(weights * spectrum**2) if total > 0 else n_grid
    return NoiseFloor(float(total / n_grid), spectrum, float(min(dof / n_grid, 1.0)), **kwargs)


def unsettled_signals(y_list, period):
    """Signals of several periods whose periods differ far more than the
    other signals' do: not in steady state.

    The spread over the periods (a slow trend removed, as in
    :func:`drift_free_variance`) of each signal is compared with the
    smallest of the others' spreads, the sensor's noise where one signal
    settled (a median would not do: a cubic spring of 1e9 N/m^3 at 50 N
    rms is chaotic on three of four multisine realisations).  Above
    ``SETTINGS.unsettled_ratio`` times that, the signal never settled: a response
    that is chaotic on that realisation (a stiff backlash driven hard), a
    record started before the transient died, or a structure that changed
    during that record.  No periodic simulation can follow such a signal,
    and its spread is not the sensor's noise.  Needs two signals of two
    periods or more; returns their indices.
    """
    if period is None:
        return []
    spread = {}
    for i, y in enumerate(y_list):
        s = drift_free_variance([y], period)
        if s is not None:
            spread[i] = float(np.sum(s))
    if len(spread) < 2:
        return []
    return [i for i, s in spread.items()
            if s > SETTINGS.unsettled_ratio * min(t for j, t in spread.items() if j != i)]


def estimate_noise(y_list, period):
    """:class:`NoiseFloor` from the period-to-period spread of the signals
    of two periods or more (None if there is none)."""
    if period is None:
        return None
    s = drift_free_variance(y_list, period)
    if s is None:
        return None
    multi = [y.size // period for y in y_list if is_periodic(y.size, period) and y.size >= 2 * period]
    return _from_spectrum(s, period, source="periods", detail=(
        f"spread over the periods of {len(multi)} training signal{'s' * (len(multi) > 1)} "
        f"({'/'.join(map(str, sorted(set(multi))))} periods)"))


def free_of_input(power):
    """The bins of an input's power spectrum ``SETTINGS.non_excited_db``
    below its strongest one (DC never counts): free of input."""
    free = power < power[1:].max() * 10 ** (SETTINGS.non_excited_db / 10)
    free[0] = False
    return free


def banded_spectrum(records, fs, n_grid):
    """Noise spectrum on the unitary DFT grid of ``n_grid`` samples from
    powers read at scattered lines of records of any length.

    ``records`` holds ``(power, usable, n)``: the unitary-DFT power of an
    ``n``-sample record per bin and the bins where it is noise.  Powers are
    averaged over the usable bins of each of ``N_NOISE_BANDS`` frequency
    bands; a band with fewer than ``MIN_LINES_PER_BAND`` usable bins (the
    excited band of a full multisine) takes the level interpolated in dB
    between its neighbours, the ends extend flat.  White noise gives a flat
    spectrum; an anti-alias filter's roll-off near Nyquist stays where it
    is instead of lowering the level everywhere.  Returns ``(spectrum,
    n_lines)``, spectrum None when no band has enough lines.
    """
    edges = np.linspace(0.0, fs / 2, N_NOISE_BANDS + 1)
    total, count = np.zeros(N_NOISE_BANDS), np.zeros(N_NOISE_BANDS)
    for power, usable, n in records:
        f = np.fft.rfftfreq(n, 1 / fs)
        band = np.clip(np.searchsorted(edges, f, side="right") - 1, 0, N_NOISE_BANDS - 1)
        np.add.at(total, band[usable], power[usable])
        np.add.at(count, band[usable], 1)
    ok = count >= MIN_LINES_PER_BAND
    if not ok.any():
        return None, 0
    centres = 0.5 * (edges[:-1] + edges[1:])
    level_db = 10 * np.log10(np.maximum(total[ok] / count[ok], 1e-300))
    f_grid = np.fft.rfftfreq(n_grid, 1 / fs)
    return 10 ** (np.interp(f_grid, centres[ok], level_db) / 10), int(count[ok].sum())


def _records(u_list, y_list, period):
    """``(u, y, P)`` per signal, a steady-state periodic one averaged over
    its ``P`` periods (the noise power then drops by ``P``), any other one
    whole (``P = 1``)."""
    out = []
    for u, y in zip(u_list, y_list):
        if is_periodic(u.size, period):
            P = u.size // period
            out.append((u.reshape(P, period).mean(0), y.reshape(P, period).mean(0), P))
        else:
            out.append((u, y, 1))
    return out


def _power(x, window=None):
    """Power of the unitary DFT of ``x`` per bin; with a ``window``
    normalised so that white noise keeps its variance per bin.

    A record that is not steady-state periodic starts and ends at different
    values: its plain DFT leaks the excited band's power over every line
    (falling only as 1 / f^2), so no line looks free of input, and the
    residual's leak hides the noise.  A Hann window's leak falls as
    1 / f^6 (measured on band-limited noise, 5-150 Hz sampled at 750 Hz: 3 lines free of
    input without it, 1,800 of 4,000 with it)."""
    if window is None:
        return np.abs(np.fft.rfft(x)) ** 2 / x.size
    return np.abs(np.fft.rfft(x * window)) ** 2 / np.sum(window**2)


def _segments(n, periodic, segment=None):
    """``(slices, window)`` a record of ``n`` samples is read in: a
    periodic one whole and unwindowed; any other one through a Hann window,
    whole or, with ``segment``, in segments of that many samples (one when
    the record is shorter), spread evenly from its first sample to its last."""
    if periodic:
        return [slice(0, n)], None
    length = min(n, segment or n)
    starts = np.round(np.linspace(0, n - length, -(-n // length))).astype(int)
    return [slice(a, a + length) for a in starts], np.hanning(length)


def _grid(u_list, period):
    return period if period is not None else max(u.size for u in u_list)


def repeated_input_noise(u_list, y_list, period, fs):
    """:class:`NoiseFloor` from training signals driven by the same input.

    Two signals of one length whose inputs differ by less than
    ``SETTINGS.same_input_db`` are the same experiment run twice: half their
    output difference is noise (of the difference's two runs), at every
    line.  None without such a pair.
    """
    records = []
    n_pairs = 0
    for i in range(len(u_list)):
        for j in range(i + 1, len(u_list)):
            ui, uj = u_list[i], u_list[j]
            if ui.size != uj.size or np.sum((ui - uj) ** 2) > 10 ** (SETTINGS.same_input_db / 10) * np.sum(ui**2):
                continue
            n_pairs += 1
            # Steady-state periodic pairs: the period averages, each of
            # noise variance / P; their difference over 2 / P is the noise.
            (_, yi, P), = _records([ui], [y_list[i]], period)
            (_, yj, _), = _records([uj], [y_list[j]], period)
            d = (yi - yj) * np.sqrt(P / 2)
            power = _power(d)  # noise alone: nothing to leak, no window needed
            usable = np.ones(power.size, bool)
            usable[0] = False  # DC holds offsets, not noise
            records.append((power, usable, d.size))
    if not records:
        return None
    n_grid = _grid(u_list, period)
    spectrum, n_lines = banded_spectrum(records, fs, n_grid)
    if spectrum is None:
        return None
    return _from_spectrum(spectrum, n_grid, source="repeated_inputs", detail=(
        f"difference between training signals of the same input ({n_pairs} "
        f"pair{'s' * (n_pairs > 1)}, {n_lines} DFT lines)"))


def non_excited_noise(u_list, y_list, simulations, period, fs):
    """:class:`NoiseFloor` from the residual of the best-fitting model at
    the DFT lines the input does not excite.

    Parameters
    ----------
    u_list, y_list : list of ndarray (n_samples_i,)
        Training inputs and measured outputs.
    simulations : dict
        Model name -> its simulation of each training signal (list of
        ndarray), or None where it failed.
    period : int or None
    fs : float

    Returns
    -------
    NoiseFloor or None
        The model whose residual at the non-excited lines is smallest sets
        the floor (``detail`` names it); an upper bound on the noise.  None
        when the inputs excite every line (no band has enough free lines).

    Notes
    -----
    A line is not excited when the input's power there is ``SETTINGS.non_excited_db``
    below its strongest line (DC never counts); a record that is not
    steady-state periodic (filtered noise, a ramp, realisations with gaps)
    is read through a Hann window (see :func:`_power`), in segments of
    ``NOISE_SEGMENT`` samples when one window leaves no band enough free
    lines.  A model that captures the
    effect leaves noise alone at those lines; one that does not leaves its
    unexplained harmonics too, so the smallest residual over the models is
    the tightest bound.  The selection among a dozen models of hundreds of
    lines each biases the estimate down by well under a dB.
    """
    # segments change nothing for periodic records: retry only when one is not
    any_aperiodic = not all(is_periodic(u.size, period) for u in u_list)
    data, n_grid = _records(u_list, y_list, period), _grid(u_list, period)
    for segment in (None, NOISE_SEGMENT) if any_aperiodic else (None,):
        reads = _free_lines(data, u_list, period, fs, segment, n_grid)
        if reads is not None:
            break
    if reads is None:
        return None
    best = _best_residual(data, simulations, u_list, period, fs, reads, n_grid)
    if best is None:
        return None
    name, spectrum, n_lines = best
    pieces = f", read in Hann segments of {segment} samples" if segment else ""
    return _from_spectrum(spectrum, n_grid, source="non_excited_lines", upper_bound=True, detail=(
        f"residual of the {name} model at the {n_lines} DFT lines the input does not excite "
        f"(an upper bound; no period repeated{pieces})"))


def _free_lines(data, u_list, period, fs, segment, n_grid):
    """The lines free of input of each record (``data``, see
    :func:`_records`), read whole or in ``segment``-sample pieces
    (:func:`_segments`): per record its slices, its window and each slice's
    usable bins; None when no band has enough of them."""
    reads = []
    for (u, _, _), u_full in zip(data, u_list):
        slices, w = _segments(u.size, is_periodic(u_full.size, period), segment)
        masks = [free_of_input(_power(u[sl], w)) for sl in slices]
        reads.append((slices, w, masks))
    lines = [(np.zeros(m.size), m, sl.stop - sl.start) for slices, _, masks in reads for sl, m in zip(slices, masks)]
    return None if banded_spectrum(lines, fs, n_grid)[0] is None else reads


def _best_residual(data, simulations, u_list, period, fs, reads, n_grid):
    """The model whose residual at the lines free of input (``reads``, see
    :func:`_free_lines`) is smallest: ``(name, spectrum, n_lines)``, or
    None when no model gives a finite, nonzero level."""
    best = None
    for name, sims in simulations.items():
        if sims is None:
            continue
        records = []
        for (_, y, P), (_, y_sim, _), (slices, w, masks) in zip(data, _records(u_list, sims, period), reads):
            r = (y - y_sim) * np.sqrt(P)  # a period average: back to the noise of one period
            records.extend((_power(r[sl], w), usable, sl.stop - sl.start) for sl, usable in zip(slices, masks))
        if not np.all([np.all(np.isfinite(p)) for p, _, _ in records]):
            continue
        spectrum, n_lines = banded_spectrum(records, fs, n_grid)
        level = sum(p[m].sum() for p, m, _ in records) / max(sum(m.sum() for _, m, _ in records), 1)
        if best is None or level < best[0]:
            best = (level, name, spectrum, n_lines)
    if best is None or not best[0] > 0:
        return None  # nothing, or exactly nothing (noiseless data): no floor to speak of
    return best[1:]


def residual_noise(y_list, y_sim, n_grid, *, name="black box", source="black_box_residual"):
    """:class:`NoiseFloor` from a model's residual on some signals: the
    smallest mean square over them (the noise is the same on every signal
    of one sensor, a model's misfit is not), white over the band.

    The last resort, for data that give no other estimate (see
    :meth:`GapDiagnosis.report <sklearn_pnlss.gap.GapDiagnosis.report>`,
    which passes the black box's validation simulations): an upper bound,
    against which a candidate that reaches the model's level closes all of
    the gap.  None when a simulation is missing.
    """
    if any(s is None for s in y_sim):
        return None
    variance = min(float(np.mean((y - s) ** 2)) for y, s in zip(y_list, y_sim))
    if not (np.isfinite(variance) and variance > 0):
        return None
    return NoiseFloor(variance, np.full(n_grid // 2 + 1, variance), 1.0, source=source,
                      upper_bound=True, detail=(
                          f"validation residual of the {name} (an upper bound; no period repeated, no input "
                          f"repeated, no line free of input)"))


def gap_test(mse, noise, n_samples):
    """P-value of the hypothesis that an error of mean square ``mse`` over
    ``n_samples`` samples is noise alone.

    The scaled mean square of Gaussian noise with ``nu`` effective degrees
    of freedom is chi-square(nu) / nu.
    """
    nu = max(noise.dof_per_sample * n_samples, 1.0)
    return float(stats.chi2.sf(mse / noise.variance * nu, nu))
