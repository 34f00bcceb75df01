"""A model of an output's increments, integrated back to the output.

A drive's position, a tank's volume, any rigid-body motion integrates: the
system has a pole at z = 1 (a free mass has two, position from velocity
from force). A state-space model fitted to such an output puts that pole
just inside or just outside the unit circle, and its simulation drifts
(on the EMPS benchmark the BLA of the position misses the test record by
58.8 mm, the BLA of its increments, summed, by 13.0 mm).
Modelling the increments instead (the velocity, sample by sample) leaves
the integrator out of the fit: what is fitted is stable, and the output is
its running sum, an integrator that is exact by construction.
"""
import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.utils.validation import check_is_fitted

from ..utils.parameters import validates_parameters
from ..utils.validation import as_signal_list, is_periodic, restore_layout, signal_layout, validate_signals
from ._base import DynamicRegressorMixin
from .bla import BLAEstimator

__all__ = ["IntegratedOutputRegressor"]


def _period(estimator):
    """The period a regressor simulates with: its own ``period``, or for a
    Pipeline the first step's that has one (the later steps take it over)."""
    steps = [step for _, step in estimator.steps] if hasattr(estimator, "steps") else [estimator]
    return next((step.period for step in steps if getattr(step, "period", None) is not None), None)


def increments(y, periodic):
    """``d(t) = y(t) - y(t - 1)`` of one (n_samples, n_outputs) signal, as
    long as ``y``: each increment at the sample it ends on, so that a model
    of ``d`` sees the inputs a model of ``y`` would (its direct feedthrough
    included). Circular for a periodic signal (its steady state returns to
    its start); otherwise the first increment, which the record does not
    hold, repeats the second."""
    if periodic:
        return y - np.roll(y, 1, axis=0)
    d = np.diff(y, axis=0)
    return np.vstack([d[:1], d])


def integrated(d, start):
    """The signal whose increments are ``d`` and whose first sample is
    ``start``: ``y(t) = start + sum_{0 < k <= t} d(k)``."""
    return start + np.cumsum(d, axis=0) - d[0]


class IntegratedOutputRegressor(DynamicRegressorMixin, BaseEstimator):
    """Fit a model to the increments of the outputs; predict their sum.

    For outputs that integrate (a drive's position, a water volume, the
    displacement of a structure free to move): ``regressor`` is fitted to
    ``y(t) - y(t - 1)`` and its simulation is summed back, so the model
    holds an exact integrator that no fit can move off the unit circle.

    Parameters
    ----------
    regressor : estimator or None, default=None
        Any of the library's regressors, or a Pipeline of them (a
        :class:`~sklearn_pnlss.BLAEstimator` and the model started from
        it); None fits ``BLAEstimator()``. Cloned at fit. Signals that are
        whole periods of its ``period`` (for a Pipeline, of the first step
        that has one) are differenced circularly, as their steady state requires.

    Attributes
    ----------
    regressor_ : estimator
        The fitted model of the increments.
    output_mean_ : ndarray of shape (n_outputs,)
        Mean of the training outputs: the level a periodic prediction is
        given when no measured outputs fix it (no input can show where an
        integrator stands).
    n_features_in_ : int
        Number of inputs.
    n_outputs_ : int
        Number of outputs.

    See Also
    --------
    sklearn.compose.TransformedTargetRegressor : the same idea for
        transforms of i.i.d. targets.

    Notes
    -----
    The fit minimises the simulation error of the increments, not of the
    output: a small bias of the increments adds up over a long record. With
    ``offsets=True`` in the :class:`~sklearn_pnlss.BLAEstimator` start, the
    model holds the training increments' mean (a drift the input explains).

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.signal import lfilter
    >>> from sklearn_pnlss import BLAEstimator, IntegratedOutputRegressor
    >>> rng = np.random.default_rng(0)
    >>> def record():  # a force, the velocity it drives, the position
    ...     u = rng.standard_normal((1, 4000, 1))
    ...     v = lfilter([0.0, 0.2], [1.0, -0.8], u[0, :, 0])
    ...     return u, np.cumsum(v)[None, :, None]
    >>> (u, y), (u_new, y_new) = record(), record()
    >>> model = IntegratedOutputRegressor(BLAEstimator(1, fs=1.0)).fit(u, y)
    >>> direct = BLAEstimator(2, fs=1.0).fit(u, y)  # the integrator fitted too
    >>> def relative_error(m):
    ...     e = m.predict(u_new, y_init=y_new[:, :10]) - y_new
    ...     return float(np.sqrt(np.mean(e**2) / np.mean(y_new**2)))
    >>> relative_error(model) < 1e-3, round(relative_error(direct), 2)
    (True, 0.35)
    """

    _parameter_constraints = {"regressor": [BaseEstimator, None]}

    def __init__(self, regressor=None):
        self.regressor = regressor

    def _periodic(self, n_samples):
        return is_periodic(n_samples, _period(self.regressor_))

    @validates_parameters
    def fit(self, X, y, **fit_params):
        """Fit ``regressor`` to the increments of ``y``.

        Parameters
        ----------
        X : signals, as the regressor takes them
        y : signals with n_outputs channels, same layout and lengths
        **fit_params : dict
            Passed on to the regressor's ``fit``; a validation output
            (``y_val``, or ``<step>__y_val`` in a Pipeline) is differenced
            as ``y`` is.

        Returns
        -------
        self
        """
        if y is None:
            raise ValueError("IntegratedOutputRegressor requires y to be passed, but the target y is None.")
        self.regressor_ = clone(self.regressor) if self.regressor is not None else BLAEstimator()
        y_list, _ = as_signal_list(y, name="y")
        d = self._increments(y, y_list)
        for key, value in fit_params.items():
            if key == "y_val" or key.endswith("__y_val"):
                fit_params[key] = self._increments(value, as_signal_list(value, name=key)[0])
        self.regressor_.fit(X, d, **fit_params)
        self.n_outputs_ = y_list[0].shape[1]
        self.output_mean_ = np.mean(np.concatenate(y_list), axis=0)
        self._y_was_1d = signal_layout(y).kind == "1d"
        return self

    def _increments(self, y, y_list):
        """The increments of the signals ``y`` (in their own layout)."""
        return restore_layout([increments(s, self._periodic(s.shape[0])) for s in y_list], signal_layout(y))

    @property
    def n_features_in_(self):
        return self.regressor_.n_features_in_

    def predict(self, X, y_init=None):
        """Simulate the increments and sum them.

        Parameters
        ----------
        X : signals, as in the regressor's ``predict``
        y_init : signals or None, default=None
            The measured outputs over the first samples of each signal: the
            sum starts at their first sample, and their increments start the
            regressor's simulation (its ``y_init``). Without them a signal
            starts at zero, and a periodic one is given the training
            outputs' mean.

        Returns
        -------
        y_pred : signals in the layout of ``X``
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        windows = None if y_init is None else as_signal_list(y_init, name="y_init", min_samples=1)[0]
        if windows is not None and len(windows) != len(X_list):
            raise ValueError(f"X holds {len(X_list)} signal(s) but y_init holds {len(windows)}; pass one "
                             "window of measured outputs per input signal.")
        out = []
        for i, U in enumerate(X_list):
            head = None if windows is None else windows[i]
            if head is not None and (head.shape[0] > U.shape[0] or head.shape[1] != self.n_outputs_):
                raise ValueError(
                    f"y_init: signal {i}'s window is {head.shape[0]} x {head.shape[1]} but X's signal has "
                    f"{U.shape[0]} samples and the model {self.n_outputs_} output(s); pass the measured "
                    "outputs of the first samples only (y[:, :skip])."
                )
            if head is not None and head.shape[0] > 1:
                # The window's increments start the regressor's simulation at
                # sample 1, the first that ends an increment the window holds
                # (the sum never uses the increment into sample 0).
                d = np.empty((U.shape[0], self.n_outputs_))
                d[1:] = self.regressor_.predict(U[1:], y_init=np.diff(head, axis=0)).reshape(U.shape[0] - 1, -1)
                d[0] = d[1]
            else:
                d = self.regressor_.predict(U).reshape(U.shape[0], -1)
            y = integrated(d, np.zeros(self.n_outputs_) if head is None else head[0])
            if head is None and self._periodic(U.shape[0]):
                y += self.output_mean_ - y.mean(axis=0)
            out.append(y)
        return restore_layout(out, layout, squeeze_1d=self._y_was_1d)
