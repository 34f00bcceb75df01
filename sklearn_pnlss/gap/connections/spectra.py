"""Period-averaged spectra of steady-state periodic records, with the noise
each line carries.

Averaging ``P`` periods leaves the steady-state response and divides the
noise's variance by ``P``; the spread of the periods around their mean
says how large that noise is, line by line and sensor by sensor (the
nonparametric noise estimate of the best linear approximation).  Nothing
else in a structural test says as directly which lines of a measured
motion can be trusted.
"""
from dataclasses import dataclass

import numpy as np

from ...utils.validation import as_signal_list, is_periodic

__all__ = ["PeriodSpectra"]


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
    """

    U: np.ndarray
    Y: np.ndarray
    Y_noise: np.ndarray
    period: int
    fs: float

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
        U, Y, noise = [], [], []
        for i, (u, v) in enumerate(zip(u_list, y_list)):
            if not is_periodic(u.shape[0], period):
                raise ValueError(f"signal {i} has {u.shape[0]} samples, not a whole number of periods of "
                                 f"{period}: pass steady-state periodic records (or the right period).")
            n_periods = u.shape[0] // period - transient_periods
            if n_periods < 2:
                raise ValueError(f"signal {i} holds {n_periods} steady-state period(s) after "
                                 f"transient_periods={transient_periods}; at least 2 are needed to tell "
                                 "the response from the noise.")
            Uk = np.fft.rfft(u[transient_periods * period:].reshape(n_periods, period, -1), axis=1)
            Yk = np.fft.rfft(v[transient_periods * period:].reshape(n_periods, period, -1), axis=1)
            U.append(Uk.mean(0))
            Y.append(Yk.mean(0))
            noise.append(Yk.var(axis=0, ddof=1) / n_periods)
        return cls(np.array(U), np.array(Y), np.array(noise), int(period), float(fs))

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
        return PeriodSpectra(self.U[index], self.Y[index], self.Y_noise[index], self.period, self.fs)
