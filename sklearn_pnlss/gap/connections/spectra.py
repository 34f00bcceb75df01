"""Period-averaged spectra of steady-state periodic records, with the noise
each line carries.

Averaging ``P`` periods leaves the steady-state response and divides the
noise's variance by ``P``; the spread of the periods around their mean
says how large that noise is, line by line and sensor by sensor (the
nonparametric noise estimate of the best linear approximation).  Nothing
else in a structural test says as directly which lines of a measured
motion can be trusted.

A record of one steady-state period repeats nothing: its noise is read at
the lines the input leaves free (a multisine excites some lines of its
band, not all), averaged over frequency bands and interpolated in between
(:func:`~sklearn_pnlss.gap.verdict.noise_floor.banded_spectrum`).  Those
lines also hold what the nonlinearity puts there, so the estimate is an
upper bound, and it is all the content above the excited band: the entry
reading (:mod:`.entry`) finds nothing there to read.
"""
from dataclasses import dataclass

import numpy as np

from ...utils.validation import as_signal_list, is_periodic
from ..verdict.noise_floor import banded_spectrum, free_of_input

__all__ = ["PeriodSpectra"]


def free_lines(U):
    """The lines an input spectrum ``U`` (n_lines, n_inputs) leaves free
    (:func:`~sklearn_pnlss.gap.verdict.noise_floor.free_of_input`)."""
    return free_of_input(np.sum(np.abs(U) ** 2, axis=1))


def free_line_noise(U, Y, period, fs, signal=0):
    """Noise variance (n_lines, n_outputs) of one period's output spectrum
    ``Y``, read at the lines its input spectrum ``U`` leaves free
    (:func:`free_lines`), per output: averaged over frequency bands,
    interpolated in dB in between."""
    free = free_lines(U)
    columns = [banded_spectrum([(np.abs(y) ** 2, free, period)], fs, period)[0] for y in Y.T]
    if columns[0] is None:
        raise ValueError(f"signal {signal} is one period whose input excites nearly every line: its noise cannot be "
                         "read. Pass two periods or more of each record, or an input that leaves lines free "
                         "(a multisine on every other line).")
    return np.stack(columns, axis=1)


@dataclass(frozen=True)
class PeriodSpectra:
    """Averaged spectra of periodic records.

    Attributes
    ----------
    U : ndarray of shape (n_signals, n_lines, n_inputs), complex
        Period-averaged input spectra (``rfft`` of one period).
    Y : ndarray of shape (n_signals, n_lines, n_outputs), complex
        Period-averaged output spectra.
    Y_noise : ndarray of shape (n_signals, n_lines, n_outputs)
        Variance of ``Y`` (of the mean over the periods) at each line.
    period : int
    fs : float
    n_periods : ndarray of shape (n_signals,)
        Steady-state periods averaged per signal (one: ``Y_noise`` read at
        the lines the input leaves free, an upper bound).
    """

    U: np.ndarray
    Y: np.ndarray
    Y_noise: np.ndarray
    period: int
    fs: float
    n_periods: np.ndarray

    @classmethod
    def from_signals(cls, X, y, *, period, fs, transient_periods=0):
        """Spectra of input-output records that are whole numbers of periods.

        Parameters
        ----------
        X : signals, (n_signals, n_samples, n_inputs) or a list
        y : signals, (n_signals, n_samples, n_outputs) or a list
        period : int
            Samples per period.
        fs : float
            Sampling rate, Hz.
        transient_periods : int, default=0
            Periods at the start of each record left out (a measured
            record's first period often holds the start's transient).

        Returns
        -------
        PeriodSpectra
        """
        u_list = as_signal_list(X, name="X", min_samples=16)[0]
        y_list = as_signal_list(y, name="y", min_samples=16)[0]
        if len(u_list) != len(y_list) or any(u.shape[0] != v.shape[0] for u, v in zip(u_list, y_list)):
            raise ValueError("X and y must hold the same number of signals of the same lengths.")
        U, Y, noise, counts = [], [], [], []
        for i, (u, v) in enumerate(zip(u_list, y_list)):
            if not is_periodic(u.shape[0], period):
                raise ValueError(f"signal {i} has {u.shape[0]} samples, not a whole number of periods of "
                                 f"{period}: pass steady-state periodic records (or the right period).")
            n_periods = u.shape[0] // period - transient_periods
            if n_periods < 1:
                raise ValueError(f"signal {i} holds no steady-state period after "
                                 f"transient_periods={transient_periods}; lower transient_periods.")
            Uk = np.fft.rfft(u[transient_periods * period:].reshape(n_periods, period, -1), axis=1)
            Yk = np.fft.rfft(v[transient_periods * period:].reshape(n_periods, period, -1), axis=1)
            counts.append(n_periods)
            U.append(Uk.mean(0))
            Y.append(Yk.mean(0))
            noise.append(Yk.var(axis=0, ddof=1) / n_periods if n_periods > 1
                         else free_line_noise(Uk[0], Yk[0], period, fs, i))
        return cls(np.array(U), np.array(Y), np.array(noise), int(period), float(fs), np.array(counts))

    @property
    def freqs(self):
        """Frequency of each line, Hz."""
        return np.fft.rfftfreq(self.period, 1.0 / self.fs)

    @property
    def n_signals(self):
        return self.U.shape[0]

    def subset(self, index):
        """The spectra of the signals at ``index``."""
        index = list(index)
        return PeriodSpectra(self.U[index], self.Y[index], self.Y_noise[index], self.period, self.fs,
                             self.n_periods[index])
