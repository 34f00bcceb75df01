"""A fitted model as an object to read: its summary (sizes, poles of the
linear part, fit figures) and the export of its linear part to SciPy.

The estimators' ``summary()`` and ``to_statespace()`` methods call
:func:`summarize` and :func:`linear_statespace`; each estimator hands in its
own lines (``structure``, ``fit``).
"""
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import StateSpace

from .metrics import rms_error
from .statespace.linear import modal_parameters

__all__ = ["ModelSummary", "linear_statespace", "summarize"]


def model_fs(estimator):
    """The sampling frequency the model knows of, or None.

    ``BLAEstimator`` has an ``fs`` parameter; the nonlinear regressors take it
    from the linear start they were fitted from (``linear_model_``, or the
    start model's), so that a ``BLAEstimator(fs=...)`` first stage carries it
    through a Pipeline.
    """
    for _ in range(3):  # decoupled -> start PNLSS -> BLA at most
        fs = estimator.get_params().get("fs") if hasattr(estimator, "get_params") else None
        if fs is not None:
            return float(fs)
        nxt = getattr(estimator, "linear_model_", None)
        if nxt is None:
            nxt = getattr(estimator, "start_model_", None)
        if nxt is None:
            return None
        estimator = nxt
    return None


def linear_statespace(estimator, fs=None):
    """The linear part ``A_, B_, C_, D_`` of a fitted estimator as a
    discrete-time :class:`scipy.signal.StateSpace`.

    Parameters
    ----------
    estimator : fitted BLAEstimator, PNLSSRegressor or DecoupledPNLSSRegressor
    fs : float or None, default=None
        Sampling frequency in Hz; None: the one the model knows (``fs`` of
        the ``BLAEstimator`` it was fitted from).

    Returns
    -------
    scipy.signal.StateSpace
        With ``dt = 1 / fs``, or ``dt = True`` (discrete time, unspecified
        step) when no frequency is known.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> from sklearn_pnlss.inspection import linear_statespace
    >>> fitted = SimpleNamespace(A_=np.array([[0.5]]), B_=np.array([[1.0]]),
    ...                          C_=np.array([[1.0]]), D_=np.array([[0.0]]))
    >>> linear_statespace(fitted, fs=100.0).dt
    0.01
    """
    fs = model_fs(estimator) if fs is None else float(fs)
    dt = True if fs is None else 1.0 / fs
    return StateSpace(estimator.A_, estimator.B_, estimator.C_, estimator.D_, dt=dt)


@dataclass
class ModelSummary:
    """What a fitted model is, in numbers; ``str()`` gives the text report.

    Attributes
    ----------
    estimator : str
        ``repr`` of the estimator (its non-default parameters).
    n_states, n_inputs, n_outputs : int
    n_params : int
        All parameters, ``n_linear_params + n_nonlinear_params``.
    n_linear_params : int
        Entries of ``A, B, C, D``: ``n^2 + n m + p n + p m``.
    n_nonlinear_params : int
    fs : float or None
        Sampling frequency in Hz; None: frequencies in cycles per sample.
    poles : ndarray of complex
        Discrete-time poles of the linear part (eigenvalues of ``A_``), one
        per mode: complex pairs once (positive imaginary part), sorted by
        natural frequency.
    natural_frequencies, damping_ratios : ndarray
        Of each pole, ``s = fs log z``: ``|s| / 2 pi`` and ``-Re(s) / |s|``.
    structure : dict
        Model-specific description (degrees, branches, ...).
    fit : dict
        Figures of the fit (iterations, cost, validation error, ...).
    scores : dict
        rms simulation error on the signals given to ``summary(X, y)``:
        ``rms`` (units of y) and ``db``; empty without signals.
    """

    estimator: str
    n_states: int
    n_inputs: int
    n_outputs: int
    n_params: int
    n_linear_params: int
    n_nonlinear_params: int
    fs: float | None
    poles: np.ndarray
    natural_frequencies: np.ndarray
    damping_ratios: np.ndarray
    structure: dict = field(default_factory=dict)
    fit: dict = field(default_factory=dict)
    scores: dict = field(default_factory=dict)

    def to_dict(self):
        """Plain Python values (JSON-ready): poles as ``[real, imag]`` pairs."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["poles"] = [[float(z.real), float(z.imag)] for z in self.poles]
        out["natural_frequencies"] = [float(f) for f in self.natural_frequencies]
        out["damping_ratios"] = [float(d) for d in self.damping_ratios]
        return out

    def __str__(self):
        unit = "Hz" if self.fs else "cycles/sample"
        lines = [
            self.estimator,
            f"  signals: {self.n_inputs} input(s), {self.n_outputs} output(s); {self.n_states} states",
            f"  parameters: {self.n_params} ({self.n_linear_params} linear, "
            f"{self.n_nonlinear_params} nonlinear)",
        ]
        lines += [f"  {_label(key)}: {_fmt(value)}" for key, value in self.structure.items()]
        fs_text = f"fs = {self.fs:g} Hz" if self.fs else "no fs: frequencies in cycles/sample"
        lines.append(f"  poles of the linear part ({fs_text}):")
        for z, f, d in zip(self.poles, self.natural_frequencies, self.damping_ratios):
            pole = f"{z.real:.6f} ± {abs(z.imag):.6f}j" if abs(z.imag) > 0 else f"{z.real:.6f}"
            lines.append(f"    z = {pole:<24} |z| = {abs(z):.6f}  f = {f:9.4g} {unit}  damping = {100 * d:7.3f} %")
        if self.fit:
            lines.append("  fit: " + ", ".join(f"{_label(k)} {_fmt(v)}" for k, v in self.fit.items()))
        if self.scores:
            lines.append(f"  rms simulation error on the given signals: {self.scores['rms']:.4g} "
                         f"({self.scores['db']:.2f} dB)")
        return "\n".join(lines)

    __repr__ = __str__


def _label(key):
    return key.replace("_db", " (dB)").replace("_", " ")


def _fmt(value):
    if isinstance(value, dict):
        return ", ".join(f"{_label(k)} {_fmt(v)}" for k, v in value.items())
    if isinstance(value, (float, np.floating)):
        return f"{value:.4g}"
    if isinstance(value, (list, tuple, np.ndarray)):
        return "(" + ", ".join(_fmt(v) for v in value) + ")"
    return str(value)


def _modes(A, fs):
    """Poles (one per complex pair) with their natural frequencies and
    damping ratios, in the order of :func:`modal_parameters`."""
    freq, damp = modal_parameters(A, 1.0 if fs is None else fs)
    z = np.linalg.eigvals(A)
    z = z[np.imag(z) >= -1e-12]
    # The same key as modal_parameters' sort, so each pole meets its mode.
    z = z[np.argsort(np.abs(np.log(z.astype(complex))))]
    return z, freq, damp


def lm_fit_figures(estimator):
    """Figures of a Levenberg-Marquardt fit: iterations, the iteration
    kept, how much the cost fell over the (last) stage, and the validation
    error of the kept iterate when validation signals were given."""
    cost = estimator.cost_history_
    out = {"iterations": int(estimator.n_iter_), "kept_iteration": int(estimator.best_iteration_)}
    if cost.size and cost[0] > 0 and cost[-1] > 0:
        out["cost_change_db"] = float(10 * np.log10(cost[-1] / cost[0]))
    history = getattr(estimator, "validation_history_", None)
    if history is not None:
        out["validation_error_db"] = float(history[estimator.best_iteration_])
    return out


def summarize(estimator, X=None, y=None, fs=None, *, structure=None, fit=None):
    """The :class:`ModelSummary` of a fitted estimator.

    The estimators' ``summary`` method; see
    :meth:`sklearn_pnlss.PNLSSRegressor.summary` for an example.

    Parameters
    ----------
    estimator : fitted BLAEstimator, PNLSSRegressor or DecoupledPNLSSRegressor
    X, y : signals or None, default=None
        Signals to report the rms simulation error on.
    fs : float or None, default=None
        Sampling frequency in Hz; None: the one the model knows, else
        frequencies are in cycles per sample.
    structure, fit : dict or None, default=None
        The model-specific lines and the figures of its fit (see
        :class:`ModelSummary`).

    Returns
    -------
    ModelSummary
    """
    fs = model_fs(estimator) if fs is None else float(fs)
    A, B, C = estimator.A_, estimator.B_, estimator.C_
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    n_linear = n * n + n * m + p * n + p * m
    poles, freq, damp = _modes(A, fs)
    scores = {}
    if X is not None or y is not None:
        if X is None or y is None:
            raise ValueError("Pass both X and y to score the model in its summary, or neither.")
        y_pred = estimator.predict(X)
        scores = {"rms": rms_error(y, y_pred), "db": rms_error(y, y_pred, db=True)}
    return ModelSummary(
        estimator=repr(estimator), n_states=n, n_inputs=m, n_outputs=p,
        n_params=int(estimator.n_params_), n_linear_params=n_linear,
        n_nonlinear_params=int(getattr(estimator, "n_nonlinear_params_", 0)), fs=fs,
        poles=poles, natural_frequencies=freq, damping_ratios=damp,
        structure=dict(structure or {}), fit=dict(fit or {}), scores=scores,
    )
