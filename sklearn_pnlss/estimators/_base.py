"""What every dynamic-model estimator of the library shares: the signal
convention, periodic steady state, the rms-dB score, scikit-learn tags, and
the fitted model as an object to read (summary, export of the linear
part)."""
import inspect

from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils import TransformerTags
from sklearn.utils.validation import check_is_fitted

from ..inspection import linear_statespace, lm_fit_figures, summarize
from ..metrics import rms_error
from ..utils.handover import attach_stage, training_signals
from ..statespace.model_base import DivergenceError
from ..utils.validation import as_signal_list, is_periodic, restore_layout, signal_layout, validate_signals

__all__ = ["DynamicRegressorMixin", "SignalRegressorBase"]


class DynamicRegressorMixin(RegressorMixin):
    """The score and tags of a regressor mapping input signals to output
    signals: minus the rms simulation error in dB, several outputs, no NaN.
    """

    def score(self, X, y, sample_weight=None):
        """Minus the rms simulation error in dB (higher is better).

        A model whose simulation error is 1e-5 (in the units of ``y``) over
        all signals scores 100.

        Parameters
        ----------
        X : signals, as in :meth:`predict`
        y : signals, true outputs in the same layout
        sample_weight : None
            Not supported (kept for scikit-learn's signature).

        Returns
        -------
        float
        """
        if sample_weight is not None:
            raise ValueError("sample_weight is not supported by dynamic models; pass None.")
        return -rms_error(y, self.predict(X), db=True)

    def __setstate__(self, state):
        # A model pickled before one of its parameters existed loads with
        # that parameter at its default (a new parameter defaults to the
        # behaviour before it), so get_params, clone and repr work on it.
        super().__setstate__(state)
        for name, parameter in inspect.signature(type(self).__init__).parameters.items():
            if parameter.default is not inspect.Parameter.empty and name not in self.__dict__:
                setattr(self, name, parameter.default)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.regressor_tags.poor_score = True
        tags.target_tags.single_output = False
        tags.target_tags.multi_output = True
        tags.input_tags.allow_nan = False
        return tags


class SignalRegressorBase(DynamicRegressorMixin, BaseEstimator):
    """Base for regressors mapping input signals to output signals.

    Subclasses implement ``fit`` (starting with ``_validate_fit_data``) and
    ``_predict_signal(U, periodic)`` on one 2-D signal; this base validates
    inputs, simulates every signal in the layout it came in, and scores in
    dB.
    """

    def _validate_fit_data(self, X, y):
        if y is None:
            raise ValueError(
                f"{type(self).__name__} requires y to be passed, but the target y is None."
            )
        X, y = training_signals(X, y)
        X_list, y_list, _ = validate_signals(self, X, y, reset=True)
        # A 1-D y given with one signal asks for 1-D predictions back.
        self._y_was_1d = signal_layout(y).kind == "1d"
        self.n_outputs_ = y_list[0].shape[1]
        return X_list, y_list

    def transform(self, X):
        """Pass the signals on to the next Pipeline stage, with this fitted
        estimator attached as its start: the next stage's ``fit`` starts
        from it (see the user guide's model selection page).

        Parameters
        ----------
        X : signals, as in :meth:`predict`

        Returns
        -------
        X : the same signals, unchanged, carrying ``stage=self``
        """
        check_is_fitted(self)
        validate_signals(self, X, reset=False, min_samples=1)
        return attach_stage(X, self)

    def set_output(self, *, transform=None):
        """scikit-learn's output configuration, for Pipelines that set it.

        ``transform`` hands signals on to the next stage unchanged (3-D
        arrays or lists of signals), which have no DataFrame form: only the
        default output is available.

        Parameters
        ----------
        transform : {"default"} or None, default=None
            None or "default" keep the output as it is. "pandas" and
            "polars" raise a ValueError that says why.

        Returns
        -------
        self
        """
        if transform not in (None, "default"):
            raise ValueError(
                f"{type(self).__name__}.set_output(transform={transform!r}): transform passes "
                "the signals on to the next Pipeline stage unchanged, as (n_signals, "
                "n_samples, n_channels) arrays or lists of signals, which have no "
                f"{transform} form. Leave the output at its default, and convert the "
                "predictions yourself (e.g. pandas.DataFrame(y_pred[i]) for signal i)."
            )
        return self

    def fit_transform(self, X, y, **fit_params):
        """:meth:`fit`, then :meth:`transform` (the Pipeline hand-over)."""
        return self.fit(X, y, **fit_params).transform(X)

    def _period(self):
        """The period the model simulates with: ``period_`` once fitted (it
        may come from the Pipeline stage before), else ``period``."""
        return self.period_ if hasattr(self, "period_") else getattr(self, "period", None)

    def _signal_is_periodic(self, n_samples):
        return is_periodic(n_samples, self._period())

    def predict(self, X, y_init=None):
        """Simulate the model (output error, not one-step-ahead prediction).

        With ``period`` set, a signal whose length is a multiple of
        ``period`` is simulated in periodic steady state; any other signal
        starts from rest, or, with ``y_init``, from the state its first
        measured outputs show.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), a list of
            2-D signals, or one 1-D/2-D signal
            Input signals.
        y_init : signals in the layout of ``X``, or None, default=None
            The measured outputs over the first samples of each signal (its
            state-initialisation window: the field's benchmarks allow it and
            leave it out of the score, ``skip=`` in
            :mod:`sklearn_pnlss.metrics`). Each signal is then simulated from
            the state whose simulation reproduces them best in least squares
            (periodic signals too): a record cut from a longer run starts
            where the system was, not from rest. The windows may be shorter
            than the signals; a window of ``k`` samples pins at most ``k``
            times ``n_outputs`` states.

        Returns
        -------
        y_pred : signals in the layout of ``X`` with ``n_outputs`` channels
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        if y_init is None:
            out = [self._predict_signal(U, self._signal_is_periodic(U.shape[0])) for U in X_list]
        else:
            out = [self._predict_from_window(U, Y_head) for U, Y_head in zip(X_list, self._windows(y_init, X_list))]
        return restore_layout(out, layout, squeeze_1d=getattr(self, "_y_was_1d", False))

    def _windows(self, y_init, X_list):
        """``y_init`` as one (k_i, n_outputs) window per signal of ``X_list``."""
        windows, _ = as_signal_list(y_init, name="y_init", min_samples=1)
        if len(windows) != len(X_list):
            raise ValueError(
                f"X holds {len(X_list)} signal(s) but y_init holds {len(windows)}; pass one window "
                "of measured outputs per input signal."
            )
        for i, (U, Y_head) in enumerate(zip(X_list, windows)):
            if Y_head.shape[1] != self.n_outputs_:
                raise ValueError(
                    f"y_init: signal {i} has {Y_head.shape[1]} channel(s) but the model has "
                    f"{self.n_outputs_} output(s); pass the measured outputs of the first samples."
                )
            if Y_head.shape[0] > U.shape[0]:
                raise ValueError(
                    f"y_init: signal {i}'s window holds {Y_head.shape[0]} samples but X's signal "
                    f"only {U.shape[0]}; pass the outputs of the first samples only (y[:, :skip])."
                )
        return windows

    def _predict_from_window(self, U, Y_head):
        try:
            return self.model_.simulate_from_window(U, Y_head)
        except DivergenceError as exc:
            raise DivergenceError(
                f"{type(self).__name__}.predict: {exc} from the state read off y_init; the input X "
                "drives the model outside the range it was fitted on, or y_init is not the output "
                "measured with X.", sample=exc.sample,
            ) from None

    def summary(self, X=None, y=None, *, fs=None):
        """What the fitted model is: sizes, poles of its linear part, and the
        figures of its fit.

        Parameters
        ----------
        X, y : signals or None, default=None
            When given, the summary also reports the rms simulation error on
            them (in the units of ``y`` and in dB).
        fs : float or None, default=None
            Sampling frequency in Hz for the natural frequencies; None uses
            the one the model knows (``fs`` of the ``BLAEstimator`` it was
            fitted from), or cycles per sample when there is none.

        Returns
        -------
        summary : ModelSummary
            Numbers as attributes (``n_params``, ``poles``,
            ``natural_frequencies``, ``damping_ratios``, ``structure``,
            ``fit``, ``scores``), ``to_dict()`` for JSON, and the text
            report as ``str(summary)``.

        Examples
        --------
        >>> import numpy as np
        >>> from scipy.signal import lfilter
        >>> from sklearn_pnlss import BLAEstimator
        >>> from sklearn_pnlss.signals import multisine
        >>> X, _ = multisine(256, fs=100.0, f_band=(1, 40), n_periods=2, n_realizations=2, random_state=0)
        >>> # steady state of y(t) = 0.6 y(t-1) + 0.5 u(t-1): three periods from rest, keep the last
        >>> y = np.stack([np.tile(lfilter([0.0, 0.5], [1, -0.6], np.tile(x[:256, 0], 3))[-256:], 2)
        ...               for x in X])[..., None]
        >>> model = BLAEstimator(n_states=1, period=256, fs=100.0).fit(X, y)
        >>> s = model.summary()
        >>> s.n_params, round(float(s.poles[0].real), 3)
        (4, 0.6)
        """
        check_is_fitted(self)
        return summarize(self, X, y, fs=fs, structure=self._summary_structure(), fit=self._summary_fit())

    def to_statespace(self, fs=None):
        """The linear part ``A_, B_, C_, D_`` as a discrete-time
        :class:`scipy.signal.StateSpace`.

        For :class:`~sklearn_pnlss.BLAEstimator` this is the whole model; for
        the nonlinear regressors it is their linear part, the model without
        its polynomial terms (for the decoupled model, without the branches,
        their linear terms included).

        Parameters
        ----------
        fs : float or None, default=None
            Sampling frequency in Hz; None uses the one the model knows (see
            :meth:`summary`). The system's ``dt`` is ``1 / fs``, or ``True``
            (discrete time, unspecified step) when no frequency is known.

        Returns
        -------
        scipy.signal.StateSpace

        Examples
        --------
        >>> import numpy as np
        >>> from scipy.signal import lfilter
        >>> from sklearn_pnlss import BLAEstimator
        >>> from sklearn_pnlss.signals import multisine
        >>> X, _ = multisine(256, fs=100.0, f_band=(1, 40), n_periods=2, n_realizations=2, random_state=0)
        >>> y = np.stack([np.tile(lfilter([0.0, 0.5], [1, -0.6], np.tile(x[:256, 0], 3))[-256:], 2)
        ...               for x in X])[..., None]
        >>> sys = BLAEstimator(n_states=1, period=256, fs=100.0).fit(X, y).to_statespace()
        >>> sys.dt, np.round(np.linalg.eigvals(sys.A).real, 3)
        (0.01, array([0.6]))
        """
        check_is_fitted(self)
        return linear_statespace(self, fs)

    def _summary_structure(self):
        """Model-specific lines of :meth:`summary` (name -> value)."""
        return {}

    def _summary_fit(self):
        """Figures of the fit for :meth:`summary` (name -> value)."""
        return lm_fit_figures(self) if hasattr(self, "cost_history_") else {}

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        # transform is the Pipeline hand-over: signals pass through unchanged.
        tags.transformer_tags = TransformerTags(preserves_dtype=[])
        return tags
