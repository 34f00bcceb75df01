"""The decoupled polynomial nonlinear state-space model."""
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre

from ._decoupled_kernels import decoupled_jacobian, decoupled_simulate
from .model_base import DivergenceError, Segment, StateSpaceModel, unbounded
from .splines import cubic_bspline_basis

__all__ = ["DecoupledModel", "Segment", "legendre_power_matrix"]


def legendre_power_matrix(degree):
    """Power coefficients of ``P_k(t) - P_k(0)``, ``k = 1..degree``.

    Returns ``M`` of shape (degree, degree): column ``k - 1`` holds the
    coefficients of ``t, t**2, ..., t**degree`` in the Legendre polynomial
    ``P_k`` less its constant term (its value at 0).
    """
    M = np.zeros((degree, degree))
    for k in range(1, degree + 1):
        power = legendre.leg2poly(np.eye(k + 1)[k])
        M[: k, k - 1] = power[1:]
    return M

_STATE_BLOCKS = ("A", "B", "Wx", "V", "G")


@dataclass
class DecoupledModel(StateSpaceModel):
    """x(t+1) = A x + B u + Wx g(V^T s), y = C x + D u + Wy g(V^T s), s = [x; u].

    ``r`` univariate branches of the projections ``z = V^T s`` replace the
    full multivariate polynomial of a PNLSS model: polynomials
    ``g_l(z) = sum_k G[l, k] z**(k+1)`` (degrees 1..d), with ``signed`` the
    odd signed powers ``g_l(z) = sum_k G[l, k] z |z|**k``, or, with
    ``knots``, cubic splines ``g_l(z) = sum_k G[l, k] (B_k(z) - B_k(0))`` on
    uniform knots (:mod:`.splines`).

    Parameters
    ----------
    A, B, C, D : ndarray of shape (n, n), (n, m), (p, n), (p, m)
        The linear part.
    Wx : ndarray of shape (n, r)
        How the branches enter the state equation.
    Wy : ndarray of shape (p, r)
        How the branches enter the output equation; a parameter only when
        ``output_branches`` (otherwise held fixed, normally at zero).
    V : ndarray of shape (n + m, r)
        Branch directions over ``s = [x; u]``.
    G : ndarray of shape (r, d)
        ``G[l, k]`` multiplies ``z_l ** (k + 1)`` (or ``z_l |z_l| ** k``, or
        ``B_k(z_l) - B_k(0)``).
    output_branches : bool, default=False
        Whether ``Wy`` is a parameter.
    bounds : ndarray of shape (r, 2) or None, default=None
        Trusted range ``[lo, hi]`` of each branch input; outside it the
        branch is continued (see ``linear_extrapolation``). None: no bounds,
        the plain polynomials.
    linear_extrapolation : bool, default=False
        Outside ``bounds``, continue each branch along its edge tangent
        instead of holding its edge value. Holding keeps ``g`` bounded, so a
        stable ``A`` gives a bounded state for every bounded input.
    knots : ndarray of shape (r, 2) or None, default=None
        ``[first knot, spacing]`` of each branch's spline (``d - 3`` equal
        intervals; at least 4 coefficients), beyond which it follows its
        edge tangent; None: polynomial branches.
    signed : bool, default=False
        Polynomial branches in signed powers ``z |z| ** k`` (``k = 0..d-1``):
        odd functions whose even degrees are ``sign(z) z ** (k + 1)``, the
        amplitude dependence of friction, clearance and hysteresis (a term
        ``z |z|`` shifts a mode's frequency in proportion to the amplitude,
        ``z ** 3`` to its square). Not with ``knots``.
    input_directions : bool, default=True
        Whether the input rows of ``V`` are parameters. False: the branches
        read the states alone (those rows held at zero, steps never move
        them), as when the physics says the input enters linearly (a
        force on a drive, a pump's flow into a tank).

    Notes
    -----
    Parameter vector order: A, B, Wx, V, G, C, D, then Wy when
    ``output_branches`` (row-major blocks): the blocks that move the state
    first, as the Jacobian kernel expects.
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    Wx: np.ndarray
    Wy: np.ndarray
    V: np.ndarray
    G: np.ndarray
    output_branches: bool = False
    bounds: np.ndarray | None = None
    linear_extrapolation: bool = False
    knots: np.ndarray | None = None
    signed: bool = False
    input_directions: bool = True

    def __post_init__(self):
        # ``copy`` of the base copies every field with np.copy; keep the flags
        # plain bools (numba specialises the kernel on their type).
        self.output_branches = bool(self.output_branches)
        self.linear_extrapolation = bool(self.linear_extrapolation)
        self.signed = bool(self.signed)
        self.input_directions = bool(self.input_directions)
        n, m, p = self.A.shape[0], self.B.shape[1], self.C.shape[0]
        r, d = self.G.shape
        self.bounds = unbounded(r) if self.bounds is None else np.array(self.bounds, dtype=float)
        if self.knots is not None:
            if self.signed:
                raise ValueError("signed powers are a polynomial basis: spline branches (knots) cannot be signed.")
            self.knots = np.array(self.knots, dtype=float)
            if self.knots.shape != (r, 2) or d < 4 or not np.all(self.knots[:, 1] > 0):
                raise ValueError(
                    f"Spline branches need knots of shape ({r}, 2) with positive spacings and at least "
                    f"4 coefficients per branch; got knots of shape {self.knots.shape} and {d} coefficients."
                )
        expected = {
            "A": (n, n), "B": (n, m), "C": (p, n), "D": (p, m),
            "Wx": (n, r), "Wy": (p, r), "V": (n + m, r), "G": (r, d), "bounds": (r, 2),
        }
        for name, shape in expected.items():
            if getattr(self, name).shape != shape:
                raise ValueError(f"{name} must have shape {shape}; got {getattr(self, name).shape}.")
        if not self.input_directions and np.any(self.V[n:] != 0):
            raise ValueError("With input_directions=False the input rows of V must be zero (the branches read the "
                             "states alone); set V[n_states:] = 0.")

    @property
    def _block_names(self):
        out = ("Wy",) if self.output_branches else ()
        return _STATE_BLOCKS + ("C", "D") + out

    @property
    def n_branches(self):
        return self.G.shape[0]

    @property
    def degree(self):
        return self.G.shape[1]

    @property
    def splines(self):
        """Whether the branches are splines (else polynomials)."""
        return self.knots is not None

    @property
    def n_nonlinear_params(self):
        """Parameters of the branches: Wx, V and G, (2n + m + d) r (or (2n +
        d) r without ``input_directions``), plus Wy when ``output_branches``."""
        return (self.Wx.size + self.V.size - self.n_fixed_params + self.G.size
                + (self.Wy.size if self.output_branches else 0))

    @property
    def n_fixed_params(self):
        """Entries of the parameter vector held fixed: the input rows of V
        without ``input_directions``."""
        return 0 if self.input_directions else self.V.size - self.V[: self.n_states].size

    def _block_start(self, name):
        """Where block ``name`` starts in the parameter vector."""
        return sum(getattr(self, block).size for block in self._block_names[: self._block_names.index(name)])

    def _fixed_columns(self):
        """Places of the fixed entries in the parameter vector."""
        # V row-major: its input rows come after its n state rows of r entries
        return self._block_start("V") + self.n_states * self.n_branches + np.arange(self.n_fixed_params)

    def _rescaled_nonlinearity(self, state_scale, input_scale, output_scale):
        """Wx, Wy, V for :meth:`rescaled`: z = V_n^T s_n = V_n^T S^-1 s, so V
        absorbs the scaling and the branches, and their trusted ranges, are
        unchanged."""
        S_i = 1 / np.concatenate([state_scale, input_scale])
        return {
            "Wx": np.diag(state_scale) @ self.Wx, "Wy": np.diag(output_scale) @ self.Wy,
            "V": S_i[:, None] * self.V, "G": self.G.copy(), "bounds": self.bounds.copy(),
            "knots": None if self.knots is None else self.knots.copy(),
        }

    def state_matrix_at_rest(self):
        """``A + Wx diag(g'(0)) V_x^T``: the branches' slopes at rest (their
        linear terms, which the fit may move) add to ``A``."""
        from ..decoupling.branches import branch_derivatives  # the decoupling package imports this module

        slope = branch_derivatives(self.G, np.zeros((1, self.n_branches)), self.bounds, self.linear_extrapolation,
                                   self.knots, self.signed)[0]
        return self.A + (self.Wx * slope) @ self.V[: self.n_states].T

    @property
    def n_null_directions(self):
        """n^2 for the state basis, and per branch: the scale shared by W
        and g, and the linear term of g that A and B absorb; for a
        polynomial, the scale shared by V and g, for a spline (whose knots
        do not scale with V), the constant that ``- B_k(0)`` cancels
        (equal coefficients)."""
        return self.n_states**2 + 3 * self.n_branches

    def bounded_variables(self, states_inputs):
        """The branch inputs ``z = V^T s`` at the points ``s = [x; u]``
        (rows): what ``bounds`` bounds."""
        return states_inputs @ self.V

    def step_basis(self, states_inputs):
        """Steps of the branch coefficients in Legendre polynomials over
        each branch's range.

        Branch ``l`` is stepped in ``P_k(z / c_l) - P_k(0)``, ``k = 1..d``,
        with ``c_l`` the largest ``|z_l|`` at the points: the same
        polynomials of degree 1..d without constant term, but nearly
        orthogonal over the range the data cover, where the powers
        ``z**(k+1)`` are nearly collinear (signed powers are stepped in the
        same combinations of theirs). Measured on Bouc-Wen (3 branches
        of degree 11, eight starts, 300 iterations;
        ``benchmarks/bench_step_basis.py``): the median start ends at
        -98.90 dB on the test multisine instead of -94.07 dB. The other
        blocks are stepped as they are.

        Parameters
        ----------
        states_inputs : array-like of shape (n_points, n_states + n_inputs)
            Rows ``[x; u]`` along the simulation of the training signals.

        Spline coefficients are stepped as they are (each acts on four
        intervals only: they are well conditioned already).

        Without ``input_directions`` the basis leaves out the fixed input
        rows of V: the steps never move them.

        Returns
        -------
        basis : ndarray of shape (n_params, n_params - n_fixed_params) or None
            Maps step coordinates to a step of ``theta`` (None: the
            parameters themselves, for spline branches with every parameter free).
        """
        if self.splines:
            return None if self.input_directions else self._without_fixed(np.eye(self.n_params))
        reach = np.abs(self._variables_by_row(states_inputs)).max(axis=1)  # a branch a row
        reach[~(reach > 0)] = 1.0
        basis = np.eye(self.n_params)
        start = self._block_start("G")
        d = self.degree
        legendre_in_powers, powers = legendre_power_matrix(d), np.arange(1, d + 1)[:, None]
        for l, c in enumerate(reach):
            i = start + l * d
            basis[i : i + d, i : i + d] = legendre_in_powers / c**powers
        return self._without_fixed(basis)

    def _without_fixed(self, basis):
        """``basis`` without the columns of the fixed parameters."""
        return basis if self.input_directions else np.delete(basis, self._fixed_columns(), axis=1)

    def _branch_arguments(self):
        """What the kernels take to evaluate the branches: the trusted
        range, the continuation, and the splines' knots and offsets
        ``B_k(0)`` (None for polynomials: the kernels are then compiled
        without the spline code, see :mod:`._decoupled_kernels`)."""
        lo, hi = self._bounds()
        if not self.splines:
            return lo, hi, self.linear_extrapolation, self.signed, None, None
        B0 = np.vstack([cubic_bspline_basis(0.0, k, self.degree)[0] for k in self.knots])
        return lo, hi, self.linear_extrapolation, False, self.knots, B0

    def _run(self, U, x0):
        return decoupled_simulate(
            self.A, self.B, self.C, self.D, self.Wx, self.Wy, self.V, self.G, *self._branch_arguments(), U, x0
        )

    def _sensitivity(self, U, x, Sx, n_skip, J):
        decoupled_jacobian(
            self.A, self.B, self.C, self.D, self.Wx, self.Wy, self.V, self.G, *self._branch_arguments(),
            U, x, Sx, n_skip, self.output_branches, J,
        )
