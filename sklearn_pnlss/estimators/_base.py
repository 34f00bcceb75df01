"""What every dynamic-model estimator of the library shares: the signal
convention, periodic steady state, the rms-dB score and scikit-learn tags."""
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils import TransformerTags
from sklearn.utils.validation import check_is_fitted

from ..metrics import rms_error
from ..utils.handover import attach_stage
from ..utils.validation import is_periodic, restore_layout, signal_layout, validate_signals

__all__ = ["SignalRegressorBase"]


class SignalRegressorBase(RegressorMixin, BaseEstimator):
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
        X_list, y_list, _ = validate_signals(self, X, y, reset=True)
        # A 1-D y given with one signal asks for 1-D predictions back.
        self._y_was_1d = signal_layout(y).kind == "1d"
        self.n_outputs_ = y_list[0].shape[1]
        return X_list, y_list

    def transform(self, X):
        """Pass the signals on to the next Pipeline stage, with this fitted
        estimator attached as its start (see
        :mod:`sklearn_pnlss.utils.handover`).

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

    def fit_transform(self, X, y, **fit_params):
        """:meth:`fit`, then :meth:`transform` (the Pipeline hand-over)."""
        return self.fit(X, y, **fit_params).transform(X)

    def _signal_is_periodic(self, n_samples):
        return is_periodic(n_samples, getattr(self, "period", None))

    def predict(self, X):
        """Simulate the model (output error, not one-step-ahead prediction).

        With ``period`` set, a signal whose length is a multiple of
        ``period`` is simulated in periodic steady state; any other signal
        starts from rest.

        Parameters
        ----------
        X : array-like of shape (n_signals, n_samples, n_inputs), a list of
            2-D signals, or one 1-D/2-D signal
            Input signals.

        Returns
        -------
        y_pred : signals in the layout of ``X`` with ``n_outputs`` channels
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        out = [self._predict_signal(U, self._signal_is_periodic(U.shape[0])) for U in X_list]
        return restore_layout(out, layout, squeeze_1d=getattr(self, "_y_was_1d", False))

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

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.regressor_tags.poor_score = True
        tags.target_tags.single_output = False
        tags.target_tags.multi_output = True
        tags.input_tags.allow_nan = False
        # transform is the Pipeline hand-over: signals pass through unchanged.
        tags.transformer_tags = TransformerTags(preserves_dtype=[])
        return tags
