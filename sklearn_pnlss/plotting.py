"""Figures users of the field expect. matplotlib is imported on first use,
so the library works without it.

Every function draws on the ``ax`` (or ``axes``) it is given, or on a new
figure, and returns the axes so that titles, limits and saving stay in the
caller's hands.
"""
import numpy as np

from .metrics import to_db
from .utils.validation import as_signal_list

__all__ = [
    "plot_bla",
    "plot_branches",
    "plot_error_spectra",
    "plot_grid_search",
    "plot_hysteresis",
    "plot_level_modes",
    "plot_time_errors",
]


def _axes(ax, **subplots):
    if ax is not None:
        return ax.figure, ax
    import matplotlib.pyplot as plt

    return plt.subplots(**subplots)


def plot_bla(estimator, ax=None, output=0, input=0):
    """FRF of a fitted :class:`~sklearn_pnlss.BLAEstimator` in dB with the
    model's FRF, the noise and nonlinear-distortion levels (standard
    deviations of the averaged estimate) and the model's error.

    Parameters
    ----------
    estimator : fitted BLAEstimator
    ax : matplotlib.axes.Axes or None, default=None
        Where to draw; None: a new figure.
    output, input : int, default=0
        Which output and input channel.

    Returns
    -------
    matplotlib.axes.Axes
        Lines in order: the nonparametric BLA, the model, the total, noise
        and nonlinear-distortion standard deviations (those that can be
        estimated), the model error.
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
    """Output spectrum and the spectra of each model's simulation error, in
    dB (``20 log10`` of the DFT amplitude divided by the square root of the
    number of samples, so that white noise of rms ``e`` lies at
    ``20 log10(e)``).

    Parameters
    ----------
    y_true : array-like of shape (n_samples,)
        Measured output (one signal, one output; a steady-state period gives
        clean lines).
    predictions : dict of str to array-like
        Simulated outputs by model name.
    fs : float
        Sampling frequency in Hz.
    ax : matplotlib.axes.Axes or None, default=None

    Returns
    -------
    matplotlib.axes.Axes
        One line for the output, then one per model (its error).

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.plotting import plot_error_spectra
    >>> y = np.sin(2 * np.pi * 5 * np.arange(200) / 100)
    >>> ax = plot_error_spectra(y, {"model": 0.99 * y}, fs=100.0)
    >>> [line.get_label() for line in ax.get_lines()]
    ['output', 'model error']
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
    """Simulation errors over time (e.g. on the swept sine), over the output
    in grey.

    Parameters
    ----------
    y_true : array-like of shape (n_samples,)
        Measured output (one signal, one output).
    predictions : dict of str to array-like
        Simulated outputs by model name.
    fs : float
        Sampling frequency in Hz.
    ax : matplotlib.axes.Axes or None, default=None

    Returns
    -------
    matplotlib.axes.Axes
        One line for the output, then one per model (its error
        ``y_true - prediction``).

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.plotting import plot_time_errors
    >>> y = np.sin(2 * np.pi * np.arange(100) / 20)
    >>> ax = plot_time_errors(y, {"model": 0.9 * y}, fs=10.0)
    >>> float(ax.get_lines()[1].get_ydata().max().round(3))
    0.1
    """
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
    """Input (vertical) against output (horizontal): the loops a hysteretic
    restoring force draws. Call it again on the same ``ax`` to overlay a
    model's loops.

    Parameters
    ----------
    u : array-like of shape (n_samples,)
        Input (e.g. force, or restoring force).
    y : array-like of shape (n_samples,)
        Output (e.g. displacement).
    ax : matplotlib.axes.Axes or None, default=None
    label : str or None, default=None
        Legend label of the curve.

    Returns
    -------
    matplotlib.axes.Axes

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.plotting import plot_hysteresis
    >>> t = np.linspace(0, 2 * np.pi, 100)
    >>> ax = plot_hysteresis(np.sin(t), np.sin(t - 0.5), label="measured")
    >>> ax = plot_hysteresis(np.sin(t), np.sin(t - 0.4), ax=ax, label="model")
    >>> len(ax.get_lines())
    2
    """
    fig, ax = _axes(ax, figsize=(5, 4))
    ax.plot(np.ravel(y), np.ravel(u), lw=0.4, label=label)
    ax.set_xlabel("output")
    ax.set_ylabel("input")
    ax.grid(alpha=0.3)
    return ax


def plot_branches(model, X=None, *, n_points=200, axes=None):
    """The branches ``g_l`` of a fitted
    :class:`~sklearn_pnlss.DecoupledPNLSSRegressor` over their training
    range, with the points where they are evaluated when the model simulates
    ``X``.

    Points outside the drawn curve's range mean the signals drive the model
    where it was not trained (extrapolation of a polynomial).

    Parameters
    ----------
    model : fitted DecoupledPNLSSRegressor
    X : signals or None, default=None
        Inputs whose simulation gives the evaluated points
        (:meth:`~sklearn_pnlss.DecoupledPNLSSRegressor.branch_inputs`).
    n_points : int, default=200
        Points of each curve.
    axes : array of matplotlib.axes.Axes or None, default=None
        One per branch; None: a new figure with a row of them.

    Returns
    -------
    ndarray of matplotlib.axes.Axes
        One per branch. On each, the evaluated points first (when ``X`` is
        given), then the curve ``g_l`` over ``z_range_``.
    """
    r = model.coef_.shape[0]
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, r, figsize=(3.6 * r, 3.4), squeeze=False)
    axes = np.ravel(axes)
    if axes.size != r:
        raise ValueError(f"axes must hold one Axes per branch ({r}); got {axes.size}.")
    z_grid, g_grid = model.branch_values(n_points=n_points)
    if X is not None:
        z_list, _ = as_signal_list(model.branch_inputs(X), name="z", min_samples=1)
        z_eval = np.concatenate(z_list)
        _, g_eval = model.branch_values(z_eval)
    for k, ax in enumerate(axes):
        if X is not None:
            ax.plot(z_eval[:, k], g_eval[:, k], ".", color="C1", ms=1.5, label="evaluated on X")
        ax.plot(z_grid[:, k], g_grid[:, k], "k", lw=1.2, label="g over training range")
        ax.set_xlabel(f"$z_{{{k + 1}}}$")
        ax.set_ylabel(f"$g_{{{k + 1}}}(z_{{{k + 1}}})$")
        ax.set_title(f"branch {k + 1}")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, markerscale=5)
    return axes


def plot_level_modes(modes, *, axes=None):
    """How each mode moves with the excitation level: its frequency shift
    from the first level (%) and its damping ratio (%) against the input
    rms, measured (solid, dots) and of the fitted model (dashed, crosses).

    Parameters
    ----------
    modes : LevelModes
        From :func:`~sklearn_pnlss.level_modes.modes_by_level`.
    axes : sequence of two matplotlib.axes.Axes or None, default=None
        Frequency shift, damping; None: a new figure with both side by side.

    Returns
    -------
    ndarray of two matplotlib.axes.Axes
        On each, per mode the measured line, then the model's when
        ``modes`` has one.
    """
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(9.0, 3.6))
    axes = np.ravel(axes)
    if axes.size != 2:
        raise ValueError(f"axes must hold two Axes (frequency shift, damping); got {axes.size}.")
    rms, ref = modes.input_rms, modes.frequencies[0]
    curves = [(modes.frequencies, modes.damping, "-o", "")]
    if modes.model_frequencies is not None:
        curves.append((modes.model_frequencies, modes.model_damping, "--x", " (model)"))
    for k in range(ref.size):
        for freq, damp, style, suffix in curves:
            label = f"{ref[k]:.3g}{suffix}"
            axes[0].plot(rms, 100 * (freq[:, k] / ref[k] - 1), style, color=f"C{k % 10}", ms=4, label=label)
            axes[1].plot(rms, 100 * damp[:, k], style, color=f"C{k % 10}", ms=4, label=label)
    axes[0].set_ylabel("frequency shift from the first level (%)")
    axes[1].set_ylabel("damping ratio (%)")
    for ax in axes:
        ax.set_xlabel("input rms")
        ax.grid(alpha=0.3)
    axes[1].legend(fontsize=7, title="mode", title_fontsize=7)
    return axes


def _grid_values(results, name):
    """Values of a parameter (``param_<name>``) or a result column
    (``name`` or ``mean_test_<name>``) of ``cv_results_``."""
    for key in (f"param_{name}", name, f"mean_test_{name}"):
        if key in results:
            return np.asarray(np.ma.getdata(results[key]), dtype=object), key
    raise KeyError(
        f"{name!r} is neither a searched parameter nor a result of cv_results_; "
        f"parameters: {sorted(k[6:] for k in results if k.startswith('param_'))}."
    )


def plot_grid_search(cv_results, x, *, group=None, score="score", ax=None):
    """Error of the candidates of a grid search against a parameter or a
    result, one line per value of another parameter: e.g. error against the
    degree for each number of branches, or against the number of parameters.

    The plotted error is minus the mean test score, in dB for the library's
    scorers (:func:`~sklearn_pnlss.metrics.rms_db_scorer`,
    :func:`~sklearn_pnlss.model_selection.mean_rms_db_scorer`). Candidates
    whose fit failed (NaN score) leave a gap.

    Parameters
    ----------
    cv_results : dict or fitted GridSearchCV
        ``cv_results_`` of a search (or the search itself).
    x : str
        Horizontal axis: a searched parameter (``"decoupled__degree"``) or a
        result column, e.g. the ``"n_nonlinear_params"`` metric of
        :func:`~sklearn_pnlss.model_selection.n_nonlinear_params_scorer`.
    group : str or None, default=None
        A searched parameter with one line per value; None: one line.
    score : str, default="score"
        Metric name: ``mean_test_<score>`` is plotted (``"score"`` for a
        single metric).
    ax : matplotlib.axes.Axes or None, default=None

    Returns
    -------
    matplotlib.axes.Axes
        One line per group value, in increasing order, points sorted by
        ``x``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.plotting import plot_grid_search
    >>> results = {  # as in GridSearchCV's cv_results_
    ...     "param_dec__n_branches": np.array([1, 1, 2, 2], dtype=object),
    ...     "param_dec__degree": np.array([3, 5, 3, 5], dtype=object),
    ...     "mean_test_score": np.array([80.0, 81.0, 90.0, 93.0]),  # minus the error in dB
    ... }
    >>> ax = plot_grid_search(results, "dec__degree", group="dec__n_branches")
    >>> [line.get_ydata().tolist() for line in ax.get_lines()]
    [[-80.0, -81.0], [-90.0, -93.0]]
    """
    results = getattr(cv_results, "cv_results_", cv_results)
    key = f"mean_test_{score}"
    if key not in results:
        raise KeyError(f"cv_results has no {key!r}; metrics: "
                       f"{sorted(k[10:] for k in results if k.startswith('mean_test_'))}.")
    error = -np.asarray(results[key], dtype=float)
    xs, x_key = _grid_values(results, x)
    groups = _grid_values(results, group)[0] if group is not None else np.zeros(len(error), dtype=object)
    fig, ax = _axes(ax, figsize=(6, 4))
    for i, g in enumerate(sorted(set(groups.tolist()))):
        sel = np.flatnonzero(groups == g)
        sel = sel[np.argsort(xs[sel].astype(float), kind="stable")]
        label = None if group is None else f"{group.split('__')[-1]} = {g}"
        ax.plot(xs[sel].astype(float), error[sel], "o-", color=f"C{i}", label=label)
    ticks = np.unique(xs.astype(float))
    if x_key.startswith("param_") and ticks.size <= 12:
        ax.set_xticks(ticks)  # the searched values, not matplotlib's fractions
    label = x.split("__")[-1].replace("_", " ")
    ax.set_xlabel("number of " + label[2:] if label.startswith("n ") else label)
    ax.set_ylabel("rms simulation error (dB)")
    ax.grid(alpha=0.3)
    if group is not None:
        ax.legend(fontsize=8)
    return ax
