"""Starts of a decoupled model: from a full PNLSS model, or from a linear
model alone.

From a full model (:func:`decoupled_start`): the nonlinear part of a PNLSS
model, ``f(s) = [E zeta(s); F eta(s)]`` with ``s = [x; u]``, is sampled
along a simulated trajectory, its Jacobian tensor is decomposed (CPD) and
the branch derivatives are fitted and integrated (see
:mod:`sklearn_pnlss.decoupling`). The result ``W g(V^T s)`` gives the
starting point of a :class:`~sklearn_pnlss.statespace.decoupled.DecoupledModel`.

From a linear model (:func:`random_branches_start`): random branch
directions over the linear model's states and input, branches of unit
size on them, and ``W = 0``, so the start is the linear model itself. The
full polynomial has a number of coefficients that grows with the cube of
the state count (2,750 at ten states, degrees 2 and 3); a model meant for
large structures cannot afford to fit it first.
"""
import math
import numbers

import numpy as np
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_array

from ..statespace.decoupled import DecoupledModel
from .branches import fit_branches, splines_from_polynomials
from .cpd import decompose_jacobian
from .jacobian_tensor import polynomial_jacobian, sample_points

__all__ = ["decoupled_start", "nonlinear_jacobian_tensor", "random_branches_start"]


def _split_linear(M, exponents, n):
    """Columns of a polynomial's coefficients ``M`` by the total degree of
    their monomial: the linear part (as matrices over x and u) and the
    coefficients / exponents of degree >= 2. Constant terms are dropped (the
    model has no constant offsets)."""
    exponents = np.asarray(exponents, dtype=np.int64)
    degree = exponents.sum(axis=1)
    lin_x = np.zeros((M.shape[0], n))
    lin_u = np.zeros((M.shape[0], exponents.shape[1] - n))
    for j in np.flatnonzero(degree == 1):
        v = int(np.argmax(exponents[j]))
        if v < n:
            lin_x[:, v] += M[:, j]
        else:
            lin_u[:, v - n] += M[:, j]
    keep = degree >= 2
    return lin_x, lin_u, M[:, keep], exponents[keep]


def _jacobian_tensor(E, exE, F, exF, points):
    J = polynomial_jacobian(E, exE, points)
    if F.shape[1] > 0:
        J = np.concatenate([J, polynomial_jacobian(F, exF, points)], axis=0)
    return J


def nonlinear_jacobian_tensor(pnlss_model, points):
    """Jacobian tensor (n [+ p], n + m, N) of the nonlinear part
    ``[E zeta(s); F eta(s)]`` of a PNLSS model (degree >= 2 terms) at the
    points ``s = [x; u]``: what the CPD decomposes."""
    n = pnlss_model.A.shape[0]
    *_, E, exE = _split_linear(np.asarray(pnlss_model.E, dtype=np.float64), pnlss_model.exE, n)
    *_, F, exF = _split_linear(np.asarray(pnlss_model.F, dtype=np.float64), pnlss_model.exF, n)
    return _jacobian_tensor(E, exE, F, exF, np.asarray(points, dtype=np.float64))


def decoupled_start(pnlss_model, states_inputs, n_branches, degree, *, n_points=500, n_knots=None,
                    signed=False, random_state=None):
    """Decoupled model that approximates a PNLSS model's polynomial.

    Parameters
    ----------
    pnlss_model : PNLSSModel
        Full polynomial model ``x(t+1) = A x + B u + E zeta(s)``,
        ``y = C x + D u + F eta(s)``.
    states_inputs : array-like of shape (n_samples, n + m)
        Trajectory ``s(t) = [x(t); u(t)]`` of a simulation of the training
        inputs; the points of the Jacobian tensor are drawn from it.
    n_branches : int
        Number of branches ``r`` (rank of the CPD).
    degree : int
        Degree ``d >= 2`` of the branches.
    n_points : int, default=500
        Number of sampling points.
    n_knots : int or None, default=None
        Spline branches with this many knots (``n_knots + 2``
        coefficients), fitted to the polynomial branches over the sampled
        points; None: the polynomial branches.
    signed : bool, default=False
        Polynomial branches in signed powers ``z |z| ** k`` (see
        :class:`~sklearn_pnlss.statespace.decoupled.DecoupledModel`), fitted
        to the branch derivatives the CPD samples.
    random_state : int, RandomState, Generator or None, default=None
        Controls the sampling points and the random start of the CPD.

    Returns
    -------
    model : DecoupledModel
        ``A, B, C, D`` of the PNLSS model, ``Wx`` and ``Wy`` the state and
        output rows of the CPD's ``W`` and ``V`` its directions, ``G`` of
        shape (r, d) with ``G[:, 0] = 0``. ``output_branches`` is True when
        ``F`` has columns.
    cpd_error : float
        Relative Frobenius error of the CPD of the Jacobian tensor.

    Notes
    -----
    The CPD's ``W`` and ``V`` have unit-norm columns and ``H`` carries the
    scale, ``H[k, l] ~ g_l'(V[:, l] . s_k)``; the branches fitted against
    ``z = V^T s`` with these very factors therefore give
    ``W g(V^T s) ~ f(s)`` without any rescaling.

    The branches have no linear term (``G[:, 0] = 0``): the linear part of
    the model stays in ``A, B, C, D``. Degree-1 monomials of ``E`` / ``F``, if
    any, are added to ``A, B`` / ``C, D`` and left out of the tensor;
    constant monomials are dropped.

    Raises ``ValueError`` when the polynomial is zero on the points (nothing
    to decouple).
    """
    n = pnlss_model.A.shape[0]
    m = pnlss_model.B.shape[1]
    p = pnlss_model.C.shape[0]
    states_inputs = check_array(states_inputs, dtype=np.float64, input_name="states_inputs")
    if states_inputs.shape[1] != n + m:
        raise ValueError(
            f"states_inputs must have n_states + n_inputs = {n + m} columns ([x; u]); "
            f"got {states_inputs.shape[1]}."
        )
    if not isinstance(degree, numbers.Integral) or isinstance(degree, bool) or degree < 2:
        raise ValueError(f"degree must be an integer >= 2; got {degree!r}.")
    degree = int(degree)
    # One random stream for both the points and the CPD start, so an int seed
    # fixes the whole start.
    rng = random_state if isinstance(random_state, np.random.Generator) else check_random_state(random_state)

    Ex_lin, Eu_lin, E, exE = _split_linear(np.asarray(pnlss_model.E, dtype=np.float64), pnlss_model.exE, n)
    Fx_lin, Fu_lin, F, exF = _split_linear(np.asarray(pnlss_model.F, dtype=np.float64), pnlss_model.exF, n)
    output_branches = pnlss_model.F.shape[1] > 0

    points = sample_points(states_inputs, n_points=n_points, random_state=rng)
    J = _jacobian_tensor(E, exE, F, exF, points)
    W, V, H, cpd_error = decompose_jacobian(J, n_branches, random_state=rng)
    G = fit_branches(V, H, points, degree, signed=signed)
    knots = None
    if n_knots is not None:
        G, knots = splines_from_polynomials(G, points @ V, n_knots + 2)
    model = DecoupledModel(
        A=pnlss_model.A + Ex_lin,
        B=pnlss_model.B + Eu_lin,
        C=pnlss_model.C + Fx_lin,
        D=pnlss_model.D + Fu_lin,
        Wx=np.ascontiguousarray(W[:n]),
        Wy=np.ascontiguousarray(W[n:]) if output_branches else np.zeros((p, W.shape[1])),
        V=np.ascontiguousarray(V),
        G=G,
        output_branches=output_branches,
        knots=knots,
        signed=signed,
    )
    return model, cpd_error


def random_branches_start(linear_model, states_inputs, n_branches, degree, *, n_knots=None, signed=False,
                          input_directions=True, random_state=None):
    """Decoupled model that equals a linear model, with random branches ready
    to grow.

    Levenberg-Marquardt from ``W = 0`` first moves ``W`` (the only branch
    parameters the output depends on there); once the branches enter the
    model, their directions and coefficients follow. Each start draws other
    directions, so several starts explore several basins, as the toolbox
    literature does.

    Parameters
    ----------
    linear_model : state-space model with ``A, B, C, D``
        The linear start (normalised: unit-rms states and input).
    states_inputs : array-like of shape (n_samples, n + m)
        Trajectory ``s(t) = [x(t); u(t)]`` of the linear model on the
        training inputs: the directions are scaled so that each branch input
        ``z_l = V[:, l] . s`` has unit rms along it.
    n_branches : int
    degree : int
        ``d >= 2``.
    n_knots : int or None, default=None
        Spline branches with this many knots (``n_knots + 2``
        coefficients) spanning the branch inputs along ``states_inputs``,
        fitted to the random polynomials of degree ``degree``: the same
        functions as the polynomial start over the knots. None: the
        polynomial branches.
    signed : bool, default=False
        Polynomial branches in signed powers ``z |z| ** k`` (the same
        coefficients on the signed basis).
    input_directions : bool, default=True
        False: directions over the states alone (the input rows of ``V``
        zero, held so by the fit).
    random_state : int, RandomState, Generator or None, default=None
        Controls the directions and the branches' coefficients.

    Returns
    -------
    model : DecoupledModel
        The linear part of ``linear_model``, ``Wx = Wy = 0``, ``V`` with
        Gaussian columns scaled to unit-rms branch inputs, and ``G`` with
        the linear term zero (it is in ``A, B``) and the others drawn from a
        standard normal divided by the factorial of their degree, so that no
        single power dominates on unit-size inputs.
    """
    A, B, C, D = (np.asarray(getattr(linear_model, k), dtype=np.float64) for k in "ABCD")
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    states_inputs = check_array(states_inputs, dtype=np.float64, input_name="states_inputs")
    if states_inputs.shape[1] != n + m:
        raise ValueError(
            f"states_inputs must have n_states + n_inputs = {n + m} columns ([x; u]); "
            f"got {states_inputs.shape[1]}."
        )
    rng = random_state if isinstance(random_state, np.random.Generator) else check_random_state(random_state)
    V = rng.standard_normal((n + m, n_branches))
    if not input_directions:
        V[n:] = 0.0
    rms = np.sqrt(np.mean((states_inputs @ V) ** 2, axis=0))
    V /= np.where(rms > 0, rms, 1.0)
    powers = np.arange(1, degree + 1)
    # float factorials: from degree 21 on, integer ones overflow int64 and
    # would give an object array that the compiled kernels cannot take
    G = rng.standard_normal((n_branches, degree)) / np.array([float(math.factorial(k)) for k in powers])
    G[:, 0] = 0.0
    knots = None
    if n_knots is not None:
        G, knots = splines_from_polynomials(G, states_inputs @ V, n_knots + 2)
    return DecoupledModel(
        A=A.copy(), B=B.copy(), C=C.copy(), D=D.copy(), Wx=np.zeros((n, n_branches)),
        Wy=np.zeros((p, n_branches)), V=np.ascontiguousarray(V), G=G, knots=knots, signed=signed,
        input_directions=input_directions,
    )
