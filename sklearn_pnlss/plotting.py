"""Figures users of the field expect. matplotlib is imported on first use,
so the library works without it."""
import numpy as np

from .metrics import to_db

__all__ = ["plot_bla", "plot_error_spectra", "plot_time_errors", "plot_hysteresis"]


def _axes(ax, **subplots):
    if ax is not None:
        return ax.figure, ax
    import matplotlib.pyplot as plt

    return plt.subplots(**subplots)


def plot_bla(estimator, ax=None, output=0, input=0):
    """FRF of a fitted :class:`~sklearn_pnlss.BLAEstimator` in dB with the
    model's FRF, the noise and nonlinear-distortion levels (standard
    deviations of the averaged estimate), and, for periodic data, the output
    levels at the non-excited odd and even detection lines.

    Returns
    -------
    matplotlib.axes.Axes
    """
    fig, ax = _axes(ax, figsize=(8, 4.5))
    f = estimator.frequencies_
    G = estimator.frf_[:, output, input]
    ax.plot(f, to_db(np.abs(G)), "k", lw=1.2, label="BLA (nonparametric)")
    ax.plot(f, to_db(np.abs(estimator.frf_model_[:, output, input])), "C1--", lw=1, label="linear model")
    for var, label, style in (
        (estimator.frf_var_total_, "total std (noise + NL)", "C3"),
        (estimator.frf_var_noise_, "noise std", "C0"),
        (estimator.frf_var_nonlinear_, "nonlinear distortion std", "C2"),
    ):
        v = var[:, output, input]
        # A zero estimate (distortion below the noise) has no level: leave a gap.
        level = np.full(v.shape, np.nan)
        np.log10(v, out=level, where=np.isfinite(v) & (v > 0))
        if np.any(np.isfinite(level)):
            ax.plot(f, 10 * level, style, lw=0.8, label=label)
    ax.plot(f, to_db(np.abs(G - estimator.frf_model_[:, output, input])), "C4:", lw=0.8, label="model error")
    ax.set_xlabel("frequency (Hz)" if estimator.fs else "frequency (cycles/sample)")
    ax.set_ylabel("amplitude (dB)")
    ax.set_title("Best linear approximation")
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    return ax


def _spectrum_db(y):
    """One-sided amplitude spectrum in dB of a 1-D signal, per sample."""
    Y = np.fft.rfft(np.asarray(y, dtype=float)) / np.sqrt(len(y))
    return to_db(np.abs(Y) + 1e-300)


def plot_error_spectra(y_true, predictions, fs, ax=None):
    """Output spectrum and the spectra of each model's simulation error.

    Parameters
    ----------
    y_true : array-like of shape (n_samples,)
        Measured output (one signal, one output; a steady-state period gives
        clean lines).
    predictions : dict of str to array-like
        Simulated outputs by model name.
    fs : float
        Sampling frequency in Hz.
    """
    fig, ax = _axes(ax, figsize=(8, 4.5))
    y_true = np.ravel(y_true)
    f = np.fft.rfftfreq(len(y_true), 1 / fs)
    ax.plot(f, _spectrum_db(y_true), "k.", ms=1.5, label="output")
    for i, (name, y_pred) in enumerate(predictions.items()):
        ax.plot(f, _spectrum_db(y_true - np.ravel(y_pred)), ".", ms=1.5, color=f"C{i}", label=f"{name} error")
    ax.set_xlabel("frequency (Hz)")
    ax.set_ylabel("amplitude (dB)")
    ax.legend(markerscale=6, fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def plot_time_errors(y_true, predictions, fs, ax=None):
    """Simulation errors over time (e.g. on the swept sine)."""
    fig, ax = _axes(ax, figsize=(8, 4))
    y_true = np.ravel(y_true)
    t = np.arange(len(y_true)) / fs
    ax.plot(t, y_true, color="0.8", lw=0.5, label="output")
    for i, (name, y_pred) in enumerate(predictions.items()):
        ax.plot(t, y_true - np.ravel(y_pred), color=f"C{i}", lw=0.5, label=f"{name} error")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("output / error")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return ax


def plot_hysteresis(u, y, ax=None, label=None):
    """Input against output: the hysteresis loop of a restoring force."""
    fig, ax = _axes(ax, figsize=(5, 4))
    ax.plot(np.ravel(y), np.ravel(u), lw=0.4, label=label)
    ax.set_xlabel("output")
    ax.set_ylabel("input")
    ax.grid(alpha=0.3)
    return ax
