"""The average of one model fitted from several random starts.

A nonlinear state-space fit lands in one of many local minima: started
from other random branch directions (or other sampling points of the
polynomial's Jacobian), the same data give models that fit the training
signals about equally well and differ most where the training signals
say least, between the fitted amplitudes and on waveforms they do not
hold. Their errors there are partly independent, so their mean simulates
a new input better than a typical one of them, the way a bagged ensemble
predicts better than its members. The mean of models is a model too: the
parallel connection of the members, a state-space model with their states
side by side, whose output is the mean of theirs. It has all their poles,
so one member that does not return to rest makes the mean so too.
"""
from numbers import Integral

import numpy as np
from joblib import Parallel, delayed
from sklearn.base import BaseEstimator, clone
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted

from ..utils.handover import training_signals
from ..utils.parameters import Interval, validates_parameters
from ..utils.threads import side_by_side_blas
from ..utils.validation import as_signal_list, restore_layout, signal_layout, validate_signals
from ._base import DynamicRegressorMixin
from .decoupled import DecoupledPNLSSRegressor

__all__ = ["AveragedRegressor"]


def random_state_keys(estimator):
    """The parameters named ``random_state`` of an estimator and of every
    estimator nested in it (``regressor__random_state``, a Pipeline step's
    ``decoupled__random_state`` ...)."""
    return sorted(key for key in estimator.get_params(deep=True)
                  if key == "random_state" or key.endswith("__random_state"))


def _n_params(member):
    """A fitted member's parameter count (of a Pipeline: its last step's,
    the model; the stages before it only start it)."""
    step = member.steps[-1][1] if hasattr(member, "steps") else member
    return getattr(step, "n_params_", 0)


def _fit_member(regressor, seed, X, y, fit_params):
    member = clone(regressor).set_params(**{key: seed for key in random_state_keys(regressor)})
    return member.fit(X, y, **fit_params)


class AveragedRegressor(DynamicRegressorMixin, BaseEstimator):
    """Fit one regressor from ``n_estimators`` random starts and average
    their simulations.

    Each member is a clone of ``regressor`` with every ``random_state`` in
    it (its own, and those of estimators nested in it) set to its own seed,
    fitted on all the training signals; the prediction is the mean of the
    members' predictions. What the members agree on the mean keeps; where
    the data leave a fit free (between the fitted amplitudes, on a waveform
    the training signals do not hold) their errors partly cancel. It costs
    ``n_estimators`` fits and simulations, and the model has the members'
    parameters together.

    Parameters
    ----------
    regressor : estimator or None, default=None
        One of the library's regressors, a Pipeline of them, or a wrapper
        around one (:class:`AboveBandRegressor`) whose fit starts at random:
        a :class:`DecoupledPNLSSRegressor` (its branch directions or
        sampling points). Anything without a ``random_state`` in its
        parameters is refused; a :class:`PNLSSRegressor` has one, but its
        fit is deterministic (the seed only draws its check inputs), so
        its members would all be one model. Cloned for each member. None
        fits ``DecoupledPNLSSRegressor()``.
    n_estimators : int, default=3
        Number of members.
    n_jobs : int or None, default=None
        How many members are fitted at a time (joblib's convention: None
        one, -1 as many as there are cores; threads, as the library's
        compiled kernels release the GIL), each on BLAS on one thread
        while several run at once (BLAS threaded in each, two F-16 members
        contended for the cores: 123 s, against 66 s). Members that fit
        their own starts in parallel too (``n_jobs`` of the decoupled
        model) share the cores start by start, so a member whose fit ends
        early leaves its core to the others: on the F-16
        (``benchmarks/f16_lru.py``), two members of two starts each took 75
        s with ``n_jobs=2`` in both, against 90 s with each member's starts
        in turn (one member ended at 54 s), the same members bit for bit.
    random_state : int, RandomState instance or None, default=None
        The members' seeds. An int ``s`` seeds the ``k``-th member with
        ``s + k``, so the first member is the model ``regressor`` would be
        with ``random_state=s``; otherwise each member's seed is drawn from
        it. An int makes the fit reproducible: the same seeds whatever
        ``n_jobs`` (BLAS's thread count can move the members by round-off).

    Attributes
    ----------
    estimators_ : list of estimators
        The fitted members.
    seeds_ : ndarray of shape (n_estimators,)
        The seed each member was fitted with.
    n_params_ : int
        The members' parameters together (of a Pipeline, its last step's).
    n_features_in_ : int
        Number of inputs.
    n_outputs_ : int
        Number of outputs.

    See Also
    --------
    sklearn.ensemble.VotingRegressor : the mean of different estimators on
        i.i.d. samples.

    Notes
    -----
    Measured on the F-16 ground vibration test
    (``benchmarks/f16_averaged.py``; figures in ``benchmarks/F16.md``
    and the user guide's decoupling page): the mean of two or three fits
    simulates the test levels and their sine sweeps better than one fit
    does, and a member unstable at rest spoils the mean on a sweep from
    rest, so fit the members with ``stable_at_rest=True``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss import AveragedRegressor, DecoupledPNLSSRegressor
    >>> from sklearn_pnlss.datasets import make_bouc_wen
    >>> data = make_bouc_wen(n_realizations=2, n_periods=1, random_state=0)
    >>> model = DecoupledPNLSSRegressor(2, n_branches=1, degree=3, init="random", n_init=1, max_iter=5)
    >>> averaged = AveragedRegressor(model, n_estimators=2, random_state=0).fit(data.X_train, data.y_train)
    >>> averaged.seeds_.tolist(), [m.random_state for m in averaged.estimators_]
    ([0, 1], [0, 1])
    >>> members = [m.predict(data.X_test_multisine) for m in averaged.estimators_]
    >>> bool(np.allclose(averaged.predict(data.X_test_multisine), np.mean(members, axis=0)))
    True
    """

    _parameter_constraints = {
        "regressor": [BaseEstimator, None],
        "n_estimators": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Integral, None],
        "random_state": ["random_state"],
    }

    def __init__(self, regressor=None, *, n_estimators=3, n_jobs=None, random_state=None):
        self.regressor = regressor
        self.n_estimators = n_estimators
        self.n_jobs = n_jobs
        self.random_state = random_state

    def _regressor(self):
        return self.regressor if self.regressor is not None else DecoupledPNLSSRegressor()

    def _seeds(self):
        if isinstance(self.random_state, Integral):
            return self.random_state + np.arange(self.n_estimators)
        return check_random_state(self.random_state).randint(np.iinfo(np.int32).max, size=self.n_estimators)

    @validates_parameters
    def fit(self, X, y, **fit_params):
        """Fit the members, each from its own seed.

        Parameters
        ----------
        X : signals, as the regressor takes them
        y : signals with n_outputs channels, same layout and lengths
        **fit_params : dict
            Passed on to every member's ``fit`` (validation signals).

        Returns
        -------
        self
        """
        if y is None:
            raise ValueError("AveragedRegressor requires y to be passed, but the target y is None.")
        regressor = self._regressor()
        if not random_state_keys(regressor):
            raise ValueError(
                f"regressor: {type(regressor).__name__} has no random_state, so every member would be the same "
                "model. Average a regressor whose fit starts at random (DecoupledPNLSSRegressor, or a Pipeline "
                "or wrapper ending in one)."
            )
        _, y_list, _ = validate_signals(self, *training_signals(X, y), reset=True)
        self.seeds_ = self._seeds()
        with side_by_side_blas(self.n_jobs, len(self.seeds_)):
            self.estimators_ = Parallel(n_jobs=self.n_jobs, prefer="threads")(
                delayed(_fit_member)(regressor, int(seed), X, y, fit_params) for seed in self.seeds_)
        self.n_outputs_ = y_list[0].shape[1]
        self.n_params_ = int(sum(_n_params(member) for member in self.estimators_))
        self._y_was_1d = signal_layout(y).kind == "1d"
        return self

    def predict(self, X, y_init=None):
        """The mean of the members' simulations.

        Parameters
        ----------
        X : signals, as in the regressor's ``predict``
        y_init : signals or None, default=None
            The measured outputs over the first samples of each signal,
            passed on to every member's ``predict`` (each member then starts
            from the state they show to it; see
            :meth:`PNLSSRegressor.predict`).

        Returns
        -------
        y_pred : signals in the layout of ``X``
        """
        check_is_fitted(self)
        X_list, _, layout = validate_signals(self, X, reset=False, min_samples=1)
        windows = {} if y_init is None else {"y_init": as_signal_list(y_init, name="y_init", min_samples=1)[0]}
        total = [0.0] * len(X_list)
        for member in self.estimators_:
            predictions = member.predict(X_list, **windows)
            total = [t + np.asarray(p).reshape(U.shape[0], -1) for t, p, U in zip(total, predictions, X_list)]
        return restore_layout([t / len(self.estimators_) for t in total], layout, squeeze_1d=self._y_was_1d)
