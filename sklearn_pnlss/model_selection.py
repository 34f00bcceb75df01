"""Model selection on whole signals.

scikit-learn's splitters already split along the first axis, which is the
signal axis here, so ``KFold`` keeps signals whole. What the field does in
addition is to select on dedicated test signals (a multisine and a swept
sine, say) that are never used for training: :func:`held_out_signals` puts
training and test signals in one list with the one split that does that.
"""
import numpy as np
from sklearn.utils.validation import check_is_fitted

from .decoupling.cpd import rank_scan
from .decoupling.jacobian_tensor import sample_points
from .decoupling.start import nonlinear_jacobian_tensor
from .metrics import rms_error
from .utils.handover import HeldOutSignalList
from .utils.validation import as_signal_list, validate_signals

__all__ = ["cpd_rank_scan", "held_out_signals", "mean_rms_db_scorer", "n_nonlinear_params_scorer",
           "worst_rms_db_scorer"]


def held_out_signals(X_train, y_train, X_test, y_test):
    """Training and test signals in one list, with the split between them.

    Parameters
    ----------
    X_train, y_train : signals used for fitting
    X_test, y_test : signals used for scoring only (lengths may differ)

    Returns
    -------
    X, y : list of ndarray
        Training signals first, then test signals. The lists know which
        signals are for training: an estimator of the library given all of
        them fits the training signals only, so ``GridSearchCV(...,
        cv=cv)`` with its default ``refit=True`` refits the best candidate
        on ``X_train, y_train`` and never on the test signals.
    cv : list of one (train_indices, test_indices) pair
        For ``GridSearchCV(..., cv=cv)``.

    Examples
    --------
    >>> import numpy as np
    >>> X, y, cv = held_out_signals(np.zeros((2, 64, 1)), np.zeros((2, 64, 1)),
    ...                             [np.zeros((100, 1))], [np.zeros((100, 1))])
    >>> len(X), [part.tolist() for part in cv[0]]
    (3, [[0, 1], [2]])
    """
    Xa, _ = as_signal_list(X_train, name="X_train")
    ya, _ = as_signal_list(y_train, name="y_train")
    Xb, _ = as_signal_list(X_test, name="X_test")
    yb, _ = as_signal_list(y_test, name="y_test")
    if len(Xa) != len(ya) or len(Xb) != len(yb):
        raise ValueError("X_train/y_train and X_test/y_test must hold as many input as output signals.")
    train = np.arange(len(Xa))
    test = np.arange(len(Xa), len(Xa) + len(Xb))
    return HeldOutSignalList(Xa + Xb, train), HeldOutSignalList(ya + yb, train), [(train, test)]


def mean_rms_db_scorer(estimator, X, y):
    """Scorer: minus the mean over signals of each signal's rms error in dB.

    Unlike :func:`~sklearn_pnlss.metrics.rms_db_scorer`, which pools all
    samples (a 153000-sample sweep then outweighs an 8192-sample multisine),
    every test signal counts the same, as when a model is selected on both a
    multisine and a sweep.

    Examples
    --------
    >>> from sklearn_pnlss.model_selection import mean_rms_db_scorer
    >>> callable(mean_rms_db_scorer)
    True
    """
    return -float(np.mean(_per_signal_db(estimator, X, y)))


def worst_rms_db_scorer(estimator, X, y):
    """Scorer: minus the largest of the held-out signals' rms errors in dB.

    For a target that must hold on every test signal ("at or below -100 dB
    on both the multisine and the sweep"): the candidate whose worse signal
    is best wins. :func:`mean_rms_db_scorer` lets a model that is very good
    on one signal make up for one that misses on the other.

    Examples
    --------
    >>> import numpy as np
    >>> from types import SimpleNamespace
    >>> X = y = [np.ones((100, 1)), np.ones((50, 1))]
    >>> model = SimpleNamespace(predict=lambda X: [X[0] + 1e-5, X[1] + 1e-4])   # a fitted model
    >>> round(worst_rms_db_scorer(model, X, y), 2)   # the second signal's -80 dB
    80.0
    """
    return -float(np.max(_per_signal_db(estimator, X, y)))


def _per_signal_db(estimator, X, y):
    """Each signal's rms simulation error in dB."""
    y_list, _ = as_signal_list(y, name="y")
    X_list, _ = as_signal_list(X, name="X")
    pred = estimator.predict(X_list)
    return [rms_error(t, p, db=True) for t, p in zip(y_list, pred)]


def n_nonlinear_params_scorer(estimator, X=None, y=None):
    """Not a score: the number of nonlinear parameters of the fitted model
    (of a Pipeline's last step), for ``GridSearchCV`` to record beside the
    error.

    Pass it as a second metric, ``scoring={"db": mean_rms_db_scorer,
    "n_nonlinear_params": n_nonlinear_params_scorer}`` with ``refit=False``
    (or ``refit="db"``); ``cv_results_["mean_test_n_nonlinear_params"]``
    then holds each candidate's parameter count, to plot the error against
    the model size (:func:`~sklearn_pnlss.plotting.plot_grid_search`).

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> n_nonlinear_params_scorer(SimpleNamespace(n_nonlinear_params_=51))
    51.0
    """
    final = estimator[-1] if hasattr(estimator, "steps") else estimator
    return float(getattr(final, "n_nonlinear_params_", 0))


def cpd_rank_scan(pnlss, X, ranks=range(1, 9), *, n_points=500, n_init=3, random_state=None):
    """CPD error per rank of a fitted PNLSS model's nonlinear part: how many
    branches a decoupled model needs.

    The Jacobian of ``[E zeta(s); F eta(s)]`` is sampled at ``n_points``
    points of the model's own simulation of ``X`` and decomposed at each
    rank; the error drops until the rank suffices (the seed paper reads 6
    for the Bouc-Wen benchmark off such a scan, then finds 3 branches of
    higher degree enough after optimisation).

    Parameters
    ----------
    pnlss : fitted PNLSSRegressor
    X : input signals (the training inputs, typically)
    ranks : iterable of int, default=range(1, 9)
    n_points : int, default=500
    n_init : int, default=3
        CPD starts per rank; the best is reported.
    random_state : int, RandomState instance or None, default=None

    Returns
    -------
    RankScan
        ``ranks`` and the relative CPD ``errors``.
    """
    check_is_fitted(pnlss, "model_")
    X_list, _, _ = validate_signals(pnlss, X, reset=False)
    model = pnlss.model_
    trajectory = model.normalised_trajectory(X_list, pnlss.period_)
    points = sample_points(trajectory, n_points=n_points, random_state=random_state)
    J = nonlinear_jacobian_tensor(model.normalised, points)
    return rank_scan(J, list(ranks), n_init=n_init, random_state=random_state)
