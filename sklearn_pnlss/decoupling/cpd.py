"""Canonical polyadic decomposition (CPD) of a Jacobian tensor.

If ``f(s) = W g(V^T s)`` with univariate branches ``g_l``, its Jacobian is
``J_f(s) = W diag(g'(V^T s)) V^T``; stacked over ``N`` points this is
exactly the rank-``r`` CPD ``J[i, v, k] = sum_l W[i, l] V[v, l] H[k, l]``
with ``H[k, l] = g_l'(v_l^T s_k)``. Decomposing the sampled Jacobian of a
full PNLSS polynomial therefore gives the decoupled structure ``W, V`` and
samples of the branch derivatives ``H``.
"""
import numbers
from contextlib import contextmanager
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import tensorly as tl
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_array
from tensorly.cp_tensor import CPTensor
from tensorly.decomposition import parafac

from ..utils.memo import last_results

__all__ = ["CPDResult", "RankScan", "decompose_jacobian", "rank_scan"]

# ALS sweeps between two checks of the exact error (see decompose_jacobian).
_CHECK_EVERY = 10
# Seeds handed to tensorly must fit a RandomState seed (< 2**32).
_MAX_SEED = 2**31 - 1
# Ridge of the ALS normal equations, for a tensor scaled to unit norm.
_RIDGE = 1e-14


class CPDResult(NamedTuple):
    """Factors and fit of a CPD ``J[i,v,k] ~ sum_l W[i,l] V[v,l] H[k,l]``.

    A named tuple, so ``W, V, H, error = decompose_jacobian(...)`` works.
    """

    W: np.ndarray
    """Output factor, shape (n_out, rank), unit-norm columns."""
    V: np.ndarray
    """Variable factor, shape (n_vars, rank), unit-norm columns."""
    H: np.ndarray
    """Point factor, shape (N, rank); carries the scale of each term."""
    error: float
    """Relative Frobenius error ``||J - [[W, V, H]]|| / ||J||``."""


@dataclass(frozen=True)
class RankScan:
    """Best relative CPD error per rank, from :func:`rank_scan`.

    Attributes
    ----------
    ranks : ndarray of int of shape (n_ranks,)
        The ranks tried, in the order given.
    errors : ndarray of float of shape (n_ranks,)
        Smallest relative Frobenius error over the random starts.
    """

    ranks: np.ndarray
    errors: np.ndarray

    def as_dict(self):
        """``{rank: error}``."""
        return {int(r): float(e) for r, e in zip(self.ranks, self.errors, strict=True)}


@contextmanager
def _numpy_backend():
    """Run tensorly on numpy without changing the caller's backend.

    The factors are used as numpy arrays right after the call, so another
    backend (torch, cupy) set by the user must not be used here; and the
    user's choice must survive the call. ``local_threadsafe=True`` limits the
    switch to this thread, so other threads never see it.

    tensorly (0.10) restores by setting this thread's previous backend as the
    global default too; that only differs from the previous global default
    if this thread had its own thread-local backend.
    """
    context = getattr(tl, "backend_context", None)
    if context is not None:
        with context("numpy", local_threadsafe=True):
            yield
        return
    old = tl.get_backend()  # pragma: no cover - tensorly without backend_context
    tl.set_backend("numpy")  # pragma: no cover
    try:  # pragma: no cover
        yield
    finally:  # pragma: no cover
        tl.set_backend(old)


def _tensorly_seed(random_state):
    """A ``random_state`` tensorly accepts: None, a Python int or a RandomState.

    tensorly rejects numpy integers and Generators; those are converted (an
    integer to ``int``, anything else to one int seed drawn from it), so all
    the usual scikit-learn seeds work.
    """
    if random_state is None or isinstance(random_state, np.random.RandomState):
        return random_state
    if isinstance(random_state, numbers.Integral) and not isinstance(
        random_state, bool
    ):
        return int(random_state)
    return int(_draw_seeds(random_state, 1)[0])


def _draw_seeds(random_state, size):
    """``size`` int seeds drawn from an int, RandomState, Generator or None."""
    if isinstance(random_state, np.random.Generator):
        return random_state.integers(0, _MAX_SEED, size=size)
    return check_random_state(random_state).randint(0, _MAX_SEED, size=size)


def _check_rank(rank, name="rank"):
    if not isinstance(rank, numbers.Integral) or isinstance(rank, bool) or rank < 1:
        raise ValueError(f"{name} must be a positive integer; got {rank!r}.")
    return int(rank)


def _check_tensor(J):
    J = check_array(J, dtype=np.float64, allow_nd=True, ensure_2d=False, input_name="J")
    if J.ndim != 3:
        raise ValueError(
            "J must be a 3-D Jacobian tensor (n_out, n_vars, N); got an array "
            f"with {J.ndim} dimension(s)."
        )
    if not np.any(J):
        raise ValueError(
            "J is zero everywhere: the map is affine, there is no nonlinear "
            "part to decouple."
        )
    return J


def _relative_error(J, factors, norm_J):
    # Plain numpy (not tl.cp_to_tensor): also called outside _numpy_backend.
    reconstruction = np.einsum("il,vl,kl->ivk", *factors)
    return float(np.linalg.norm(J - reconstruction) / norm_J)


def _as_factors(cp):
    """Float64 factors of a tensorly CPTensor, its weights folded into the first.

    With ``normalize_factors=False`` the weights are ones; folding them in
    anyway keeps the result independent of that detail.
    """
    weights, factors = cp
    factors = [np.asarray(f, dtype=np.float64) for f in factors]
    if weights is not None:
        factors[0] = factors[0] * np.asarray(weights)
    return factors


def _balance(factors):
    """Give the three columns of each term the same norm (same product).

    ALS leaves the split of a term's scale between its factors free; letting
    it drift makes the Gram matrices badly scaled. A zero term stays zero.
    """
    norms = [np.linalg.norm(f, axis=0) for f in factors]
    alive = np.all([n > 0 for n in norms], axis=0)
    target = np.prod(norms, axis=0) ** (1.0 / 3.0)
    return [
        np.where(alive, f * (target / np.where(alive, n, 1.0)), f)
        for f, n in zip(factors, norms, strict=True)
    ]


def _normalise(W, V, H):
    """Fix the scaling, sign and order ambiguities of a CPD.

    Convention: the columns of ``W`` and ``V`` have unit 2-norm and their
    largest-magnitude entry is positive; all scale and sign go into ``H``
    (so ``H[:, l]`` samples ``g_l'`` with ``v_l`` of unit length). Terms are
    ordered by decreasing ``||H[:, l]||``, i.e. by contribution to ``J``.
    """
    W, V, H = W.copy(), V.copy(), H.copy()
    for factor in (W, V):
        norms = np.linalg.norm(factor, axis=0)
        # A zero column (a term ALS switched off) has no direction to fix.
        norms[norms == 0] = 1.0
        cols = np.arange(factor.shape[1])
        signs = np.sign(factor[np.abs(factor).argmax(axis=0), cols])
        signs[signs == 0] = 1.0
        scale = norms * signs
        factor /= scale
        H *= scale
    order = np.argsort(-np.linalg.norm(H, axis=0), kind="stable")
    return W[:, order], V[:, order], H[:, order]


def decompose_jacobian(J, rank, *, n_iter_max=2000, tol=1e-10, random_state=None):
    """Rank-``r`` canonical polyadic decomposition of a Jacobian tensor.

    Alternating least squares (``tensorly.decomposition.parafac``) from a
    random start, with line search, then polished with an exact stopping
    test (see Notes).

    Parameters
    ----------
    J : array-like of shape (n_out, n_vars, N)
        Jacobian tensor, e.g. from
        :func:`~sklearn_pnlss.decoupling.polynomial_jacobian`.
    rank : int
        Number of terms ``r`` (branches of the decoupled model).
    n_iter_max : int, default=2000
        Maximum number of ALS sweeps of each of the two phases.
    tol : float, default=1e-10
        Phase 1 stops when one sweep changes the relative error by less than
        ``tol``; phase 2 when 10 sweeps decrease it by less than ``tol``, or
        when it is below ``tol``.
    random_state : int, RandomState, Generator or None, default=None
        Random start of ALS. Different starts can end in different local
        minima: try several (see :func:`rank_scan`).

    Returns
    -------
    result : CPDResult
        Named tuple ``(W, V, H, error)``: ``W`` of shape (n_out, rank),
        ``V`` of shape (n_vars, rank), ``H`` of shape (N, rank) with
        ``J[i, v, k] ~ sum_l W[i, l] V[v, l] H[k, l]``, and ``error``, the
        relative Frobenius error ``||J - [[W, V, H]]||_F / ||J||_F``.
        Columns of ``W`` and ``V`` have unit norm with their largest-magnitude
        entry positive; scale and sign are in ``H``; terms are ordered by
        decreasing ``||H[:, l]||``.

    Notes
    -----
    Phase 1 is tensorly's ALS with its line search (extrapolation of the
    last step), which crosses the long "swamps" of slow progress caused by
    nearly collinear factors; these are common here, since the paper's
    Bouc-Wen model has more branches (r = 6) than outputs (n_out = 3).
    Without the line search, an exactly decomposable tensor with two nearly
    parallel columns of ``W`` was often still at a relative error of 1e-2
    after 2000 sweeps.

    tensorly measures convergence with the expansion
    ``||J||^2 - 2<J, [[W,V,H]]> + ||[[W,V,H]]||^2``, whose cancellation limits
    it to about 1e-8 (the square root of machine precision), so phase 1 stops
    near 1e-8 even for an exact decomposition. Phase 2 therefore continues
    with plain ALS in chunks of 10 sweeps, warm-started from the previous
    factors, and computes the error directly from the residual.

    Between chunks the three columns of each term are rescaled to equal
    norms (ALS leaves that split free and it can drift). The ALS normal
    equations carry a ridge of 1e-14 (on ``J / ||J||``), so that a rank above
    the tensor's rank, whose extra terms die out, does not stop ALS with a
    singular matrix.

    A call repeated with the same tensor, rank, ``n_iter_max``, ``tol`` and
    random start (an int, or a ``RandomState`` in the same state) returns
    the first call's result without running ALS again, and leaves a
    ``RandomState`` where the first call left it: the decoupled model's
    starts at one branch count decompose the same tensor for every branch
    degree a grid search tries. The last 32 results are kept in each
    process; ``random_state=None`` is never repeated.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> a, b, c = rng.normal(size=3), rng.normal(size=4), rng.normal(size=20)
    >>> J = np.einsum("i,v,k->ivk", a, b, c)  # a rank-1 tensor
    >>> W, V, H, error = decompose_jacobian(J, 1, random_state=0)
    >>> W.shape, V.shape, H.shape, bool(error < 1e-10)
    ((3, 1), (4, 1), (20, 1), True)
    """
    J = _check_tensor(J)
    rank = _check_rank(rank)
    if not isinstance(n_iter_max, numbers.Integral) or n_iter_max < 1:
        raise ValueError(f"n_iter_max must be a positive integer; got {n_iter_max!r}.")
    if not np.isfinite(tol) or tol < 0:
        raise ValueError(f"tol must be a non-negative number; got {tol!r}.")
    seed = _tensorly_seed(random_state)
    if seed is None:
        return _alternating_least_squares(J, rank, n_iter_max, tol, None)
    start = seed if isinstance(seed, np.random.RandomState) else np.random.RandomState(seed)
    W, V, H, error, state_after = _repeatable(J, np.array([rank, n_iter_max, tol]), _state_array(start))
    if isinstance(random_state, np.random.RandomState):  # left where the decomposition leaves it
        seed.set_state(_state_tuple(state_after))
    # copies: the kept result is read-only, and callers write into the factors
    return CPDResult(W.copy(), V.copy(), H.copy(), float(error))


def _state_array(random_state):
    """A RandomState's state as one float array (its 624 words are exact in
    float64), the form :func:`last_results` tells arguments apart by."""
    _, words, position, has_gauss, gauss = random_state.get_state()
    return np.concatenate([words.astype(np.float64), [position, has_gauss, gauss]])


def _state_tuple(state):
    """The ``RandomState.set_state`` tuple of a :func:`_state_array`."""
    return "MT19937", state[:-3].astype(np.uint32), int(state[-3]), int(state[-2]), float(state[-1])


# A grid over the branch degree at one branch count decomposes the same
# tensor from the same seeds once per degree (the tensor is the start
# model's, the seeds the estimator's): ALS ran ten times for each result,
# 4 to 5 s of a 17 to 24 s fit at 5 and 6 branches. A result is a few kB,
# its key the tensor (48 kB for Bouc-Wen, 0.6 MB for the F-16 at 10 states).
@last_results(maxsize=32)
def _repeatable(J, settings, state):
    """:func:`_alternating_least_squares` from the RandomState in ``state``
    (``settings``: rank, n_iter_max, tol), and that state after it."""
    rank, n_iter_max, tol = settings
    start = np.random.RandomState()
    start.set_state(_state_tuple(state))
    W, V, H, error = _alternating_least_squares(J, int(rank), int(n_iter_max), float(tol), start)
    return W, V, H, np.array(error), _state_array(start)


def _alternating_least_squares(J, rank, n_iter_max, tol, seed):
    """:func:`decompose_jacobian` once its arguments are checked."""
    norm_J = np.linalg.norm(J)
    # Work on J / ||J||: the ridge below and the stopping test then mean the
    # same whatever the units of the states and inputs.
    J_unit = J / norm_J

    with _numpy_backend():
        # Phase 1: tensorly's ALS with its line search, which crosses the
        # long "swamps" of slow progress that nearly collinear factors cause
        # (e.g. more branches than outputs: Bouc-Wen has n_out = 3, r = 6).
        cp = parafac(
            J_unit,
            rank,
            n_iter_max=n_iter_max,
            init="random",
            tol=tol,
            random_state=seed,
            linesearch=True,
            l2_reg=_RIDGE,
        )
        factors = _balance(_as_factors(cp))
        # Phase 2: plain ALS polish with an exact stopping test. tensorly's
        # error estimate cannot go below ~1e-8, so phase 1 stops there even
        # when the tensor has an exact decomposition.
        error = _relative_error(J_unit, factors, 1.0)
        done = 0
        while done < n_iter_max and error >= tol:
            sweeps = min(_CHECK_EVERY, n_iter_max - done)
            try:
                # tol=None switches tensorly's own stopping test off; each
                # chunk starts from the previous factors.
                cp = parafac(
                    J_unit,
                    rank,
                    n_iter_max=sweeps,
                    init=CPTensor((None, factors)),
                    tol=None,
                    l2_reg=_RIDGE,
                )
            except np.linalg.LinAlgError:  # pragma: no cover - ridge prevents it
                break  # keep the last factors that could be computed
            done += sweeps
            new_factors = _balance(_as_factors(cp))
            new_error = _relative_error(J_unit, new_factors, 1.0)
            if new_error >= error:
                break
            improvement = error - new_error
            factors, error = new_factors, new_error
            if improvement < tol:
                break

    factors[2] = factors[2] * norm_J
    W, V, H = _normalise(*factors)
    return CPDResult(W, V, H, _relative_error(J, [W, V, H], norm_J))


def rank_scan(J, ranks, *, n_init=3, n_iter_max=2000, tol=1e-10, random_state=None):
    """Best relative CPD error for each candidate rank.

    The error drops sharply until the rank at which the Jacobian is well
    described, then levels off: the knee estimates the number of branches
    (about 6 for the Bouc-Wen benchmark in the reference paper). ALS can
    end in a local minimum, so each rank keeps the best of ``n_init``
    random starts.

    Parameters
    ----------
    J : array-like of shape (n_out, n_vars, N)
        Jacobian tensor.
    ranks : iterable of int
        Ranks to try, e.g. ``range(1, 7)``.
    n_init : int, default=3
        Random starts per rank.
    n_iter_max : int, default=2000
        Maximum ALS sweeps per start.
    tol : float, default=1e-10
        ALS stopping tolerance, see :func:`decompose_jacobian`.
    random_state : int, RandomState, Generator or None, default=None
        Seeds all the starts.

    Returns
    -------
    scan : RankScan
        ``scan.ranks`` and ``scan.errors`` (arrays), ``scan.as_dict()``.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> J = np.einsum("i,v,k->ivk", *(rng.normal(size=n) for n in (3, 4, 20)))
    >>> scan = rank_scan(J, [1, 2], n_init=2, random_state=0)
    >>> scan.ranks.tolist(), bool(scan.errors[0] < 1e-10)
    ([1, 2], True)
    """
    J = _check_tensor(J)
    ranks = [ranks] if isinstance(ranks, numbers.Integral) else list(ranks)
    ranks = [_check_rank(r, name="ranks") for r in ranks]
    if not ranks:
        raise ValueError("ranks must hold at least one rank.")
    n_init = _check_rank(n_init, name="n_init")
    # All seeds are drawn up front, so the starts of one rank do not depend
    # on how many random numbers the other ranks used.
    seeds = _draw_seeds(random_state, len(ranks) * n_init).reshape(len(ranks), n_init)
    errors = np.array(
        [
            min(
                decompose_jacobian(
                    J, rank, n_iter_max=n_iter_max, tol=tol, random_state=int(seed)
                ).error
                for seed in rank_seeds
            )
            for rank, rank_seeds in zip(ranks, seeds, strict=True)
        ]
    )
    return RankScan(ranks=np.array(ranks, dtype=np.int64), errors=errors)
