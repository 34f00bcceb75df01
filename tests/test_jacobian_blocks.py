"""The Jacobian taken in blocks of samples: the same rows as in one piece
(the sensitivity recursion carries its state across blocks), and the same
normal equations, whatever the block length, with time or frequency
weights; the large products go through BLAS and agree with the loops."""
import numpy as np
import pytest

from sklearn_pnlss.statespace import objective
from sklearn_pnlss.statespace.decoupled import DecoupledModel
from sklearn_pnlss.statespace.monomials import monomial_exponents
from sklearn_pnlss.statespace.objective import SimulationError
from sklearn_pnlss.statespace.pnlss import PNLSSModel, Segment

P = 64


def _pnlss(rng, n=3, m=1, p=2, degrees=(2, 3)):
    exE = monomial_exponents(n + m, degrees)
    exF = monomial_exponents(n + m, (2,))
    return PNLSSModel(
        A=np.diag(np.linspace(0.9, 0.3, n)) + 0.03 * rng.standard_normal((n, n)),
        B=rng.standard_normal((n, m)), C=rng.standard_normal((p, n)), D=rng.standard_normal((p, m)),
        E=0.01 * rng.standard_normal((n, len(exE))), F=0.01 * rng.standard_normal((p, len(exF))),
        exE=exE, exF=exF,
    )


def _decoupled(rng, n=3, m=1, p=2, r=2, d=4):
    return DecoupledModel(
        A=np.diag(np.linspace(0.9, 0.3, n)), B=rng.standard_normal((n, m)), C=rng.standard_normal((p, n)),
        D=rng.standard_normal((p, m)), Wx=0.05 * rng.standard_normal((n, r)), Wy=np.zeros((p, r)),
        V=rng.standard_normal((n + m, r)), G=0.1 * rng.standard_normal((r, d)),
    )


@pytest.mark.parametrize("make", [_pnlss, _decoupled])
@pytest.mark.parametrize("length", [1, 7, 64, 1000])
def test_blocks_hold_the_rows_of_the_whole_jacobian(make, length):
    rng = np.random.default_rng(0)
    model = make(rng)
    seg = Segment(0.3 * rng.standard_normal((3 * P + 11, 1)), np.zeros((3 * P, 2)), 11)
    whole = model.segment_jacobian(seg)
    rows = np.concatenate([J.copy() for _, J in model.jacobian_blocks(seg, length)])
    np.testing.assert_array_equal(rows, whole)


def test_jacobian_through_blas_is_exact():
    """Ten states and their cubic monomials (2,860 state-moving columns,
    carried by BLAS) against finite differences of the simulation."""
    rng = np.random.default_rng(1)
    n = 10
    exE = monomial_exponents(n + 1, (2, 3), np.arange(n + 1) < n)
    model = PNLSSModel(
        A=np.diag(np.linspace(0.95, 0.5, n)), B=rng.standard_normal((n, 1)), C=rng.standard_normal((3, n)),
        D=np.zeros((3, 1)), E=1e-3 * rng.standard_normal((n, len(exE))), F=np.zeros((3, 0)),
        exE=exE, exF=np.zeros((0, n + 1), dtype=np.int64),
    )
    seg = Segment(0.3 * rng.standard_normal((40, 1)), np.zeros((35, 3)), 5)
    J = model.jacobian([seg])
    theta = model.theta
    for q in rng.choice(theta.size, 12, replace=False):
        d = np.zeros_like(theta)
        d[q] = 1e-6
        fd = (model.with_theta(theta + d).residual([seg]) - model.with_theta(theta - d).residual([seg])) / 2e-6
        np.testing.assert_allclose(J[:, q], fd, atol=1e-7 * np.abs(J).max())


@pytest.mark.parametrize("weighting", [None, "time", "frequency"])
def test_normal_equations_do_not_depend_on_the_block_length(weighting, monkeypatch):
    rng = np.random.default_rng(2)
    model = _pnlss(rng)
    # A periodic input, five periods of transient (0.9^320: decayed): the
    # frequency-weighted segment is periodic, its Jacobian taken in steady
    # state (model.jacobian_blocks), the others' from rest.
    U = np.tile(0.3 * rng.standard_normal((P, 1)), (8, 1))
    Y = rng.standard_normal((3 * P, 2))
    extra = {
        None: {},
        "time": {"time_weight": rng.uniform(0, 2, (3 * P, 2))},
        "frequency": {"freq_weight": rng.uniform(0, 2, (P // 2 + 1, 2)), "period": P},
    }[weighting]
    cost = SimulationError([Segment(U, Y, 5 * P, **extra)])
    J = objective.weigh(cost.segments[0], model.segment_jacobian(cost.segments[0]))
    e = cost.residual(model)
    # A block of a few samples: frequency weights round it up to a period.
    monkeypatch.setattr(objective, "JACOBIAN_BLOCK_BYTES", 8 * 2 * model.n_params * 5)
    G, g = cost.normal_equations(model)
    np.testing.assert_allclose(G, J.T @ J, rtol=1e-10, atol=1e-12 * np.abs(G).max())
    np.testing.assert_allclose(g, J.T @ e, rtol=1e-10, atol=1e-12 * np.abs(g).max())
    assert objective.block_length(cost.segments[0], 2, model.n_params) == (P if weighting == "frequency" else 5)


@pytest.mark.parametrize("make", [_pnlss, _decoupled])
def test_a_periodic_segment_is_differentiated_in_steady_state_without_its_transient(make):
    """Slow poles (0.98: the state keeps 27 % of itself over a period):
    the Jacobian from the steady-state fixed point, after a transient the
    recursion skips, equals the one carried from rest through 40 periods
    (blocks and all); the normal equations fold it in."""
    rng = np.random.default_rng(4)
    model = make(rng)
    model = model.with_theta(model.theta)  # a copy
    model.A[:] = np.diag(np.full(model.n_states, 0.98))
    u = 0.05 * rng.standard_normal((P, 1))  # small enough for the slow decoupled model to stay bounded
    Y = rng.standard_normal((2 * P, 2))
    periodic = Segment(np.tile(u, (42, 1)), Y, 40 * P, period=P)
    from_rest = Segment(periodic.U, Y, 40 * P)  # the same signal, no period: carried from rest
    assert model.steady_state_segment(periodic) and not model.steady_state_segment(from_rest)
    reference = model.segment_jacobian(from_rest)
    assert np.all(np.isfinite(reference))
    fold = {}
    blocks = np.concatenate([J.copy() for _, J in model.jacobian_blocks(periodic, 50, steady=fold)])
    n, n_sx = model.n_states, model.n_state_params
    assert blocks.shape == reference.shape[:2] + (model.n_params + n,)
    steady = blocks[..., : model.n_params].copy()
    steady[..., :n_sx] += blocks[..., model.n_params :] @ fold["S0"]
    np.testing.assert_allclose(steady, reference, rtol=1e-9, atol=1e-9 * np.abs(reference).max())
    G, g = SimulationError([periodic]).normal_equations(model)
    e = SimulationError([from_rest]).residual(model)
    R = reference.reshape(-1, model.n_params)
    np.testing.assert_allclose(G, R.T @ R, rtol=1e-9, atol=1e-9 * np.abs(G).max())
    np.testing.assert_allclose(g, R.T @ e, rtol=1e-9, atol=1e-9 * np.abs(g).max())


@pytest.mark.parametrize("weighting", [None, "time"])
def test_a_large_model_forms_its_gram_matrix_in_single_precision(weighting, monkeypatch):
    """Above SINGLE_PRECISION_PARAMS the blocks are single precision: J^T J
    agrees with the double one to single precision, and so does the
    gradient J^T e, summed in double precision from the rounded rows; with
    a periodic segment (start-state columns folded in) and with a time
    weight (which takes the rounded rows to double precision)."""
    rng = np.random.default_rng(5)
    model = _pnlss(rng, n=4, degrees=(2, 3))
    U = np.tile(0.3 * rng.standard_normal((P, 1)), (6, 1))
    Y = rng.standard_normal((2 * P, 2))
    extra = {"time_weight": rng.uniform(0, 2, (2 * P, 2))} if weighting else {"period": P}
    cost = SimulationError([Segment(U, Y, 4 * P, **extra)])
    monkeypatch.setattr(objective, "SINGLE_PRECISION_PARAMS", 10**9)
    G64, g64 = cost.normal_equations(model)
    monkeypatch.setattr(objective, "SINGLE_PRECISION_PARAMS", model.n_params - 1)
    assert objective.jacobian_dtype(model.n_params) == np.float32
    G32, g32 = cost.normal_equations(model)
    assert G32.dtype == g32.dtype == np.float64
    scale = np.sqrt(np.outer(np.diag(G64), np.diag(G64)))
    err = np.abs(G32 - G64) / scale
    assert 0.0 < err.max() < 1e-5  # rounded: single precision was used
    np.testing.assert_allclose(g32, g64, rtol=1e-5, atol=1e-6 * np.abs(g64).max())


@pytest.mark.parametrize("make", [_pnlss, _decoupled])
def test_steady_state_simulation_reuses_the_converged_period(make):
    """A signal that repeats one period is simulated in steady state by the
    converged period itself, repeated; one whose periods differ is simulated
    through from the steady-state start of its first period. Both agree
    with a simulation from that start to round-off."""
    rng = np.random.default_rng(6)
    model = make(rng)
    u = 0.05 * rng.standard_normal((P, 1))  # the decoupled model stays bounded
    x0 = model.steady_state_start(u)
    for U in (np.tile(u, (3, 1)), np.vstack([u, 0.5 * u, u])):
        reference = model.simulate(U, x0)[0]
        np.testing.assert_allclose(model.simulate_signal(U, P), reference, rtol=1e-9, atol=1e-12)
        states = model.states_inputs(U, P)
        np.testing.assert_allclose(states[:, -1:], U)
        np.testing.assert_allclose(states[:, :-1], model.simulate_states(U, x0), rtol=1e-9, atol=1e-12)


def test_single_precision_that_overflows_falls_back_to_double(monkeypatch):
    """A monomial x**5 of a state of 1e5 has a sensitivity of 1e25, whose
    square is beyond single precision: the normal equations are formed
    again in double precision, finite, and without a warning (tests turn
    warnings into errors)."""
    rng = np.random.default_rng(7)
    model = PNLSSModel(A=np.array([[0.5]]), B=np.array([[1.0]]), C=np.array([[1.0]]), D=np.zeros((1, 1)),
                       E=np.array([[1e-30]]), F=np.zeros((1, 0)), exE=np.array([[5, 0]]),
                       exF=np.zeros((0, 2), dtype=np.int64))
    seg = Segment(1e5 * rng.standard_normal((60, 1)), np.zeros((50, 1)), 10)
    cost = SimulationError([seg])
    monkeypatch.setattr(objective, "SINGLE_PRECISION_PARAMS", 10**9)
    G64, g64 = cost.normal_equations(model)
    assert np.all(np.isfinite(G64)) and np.abs(G64).max() > 1e45
    monkeypatch.setattr(objective, "SINGLE_PRECISION_PARAMS", 1)
    G, g = cost.normal_equations(model)
    np.testing.assert_array_equal(G, G64)
    np.testing.assert_array_equal(g, g64)


def test_the_columns_of_the_recursion_can_be_shared_out():
    """The sensitivity recursion run on spans of its columns (as threads
    share it out) writes the Jacobian of the whole run: spans that cut
    through the state's parameters, through the start-state columns, or at
    their border; with states held at the edge of a trusted box, inputs in
    the monomials, and the state after the run the same from every span."""
    from sklearn_pnlss.statespace._pnlss_kernels import pnlss_jacobian

    rng = np.random.default_rng(8)
    model = _pnlss(rng, n=3, m=1, p=2, degrees=(2, 3))
    model.bounds[:3] = [[-0.2, 0.2]] * 3  # the states leave it: held, no derivative there
    U = 0.5 * rng.standard_normal((80, 1))
    n, n_sx, n_par = model.n_states, model.n_state_params, model.n_params
    Sx0 = np.hstack([0.1 * rng.standard_normal((n, n_sx)), np.eye(n)])  # mid-signal, start-state columns last
    x0 = 0.1 * rng.standard_normal(n)
    assert np.abs(model.simulate_states(U, x0)).max() > 0.3
    lo, hi = model.bounds.T.copy()
    args = (model.A, model.B, model.C, model.D, model.E, model.F, model.exE, model.exF, lo, hi, U)

    def run(edges):
        J = np.full((U.shape[0] - 4, 2, n_par + n), np.nan)
        Sx, x_end = Sx0.copy(), np.empty(n)
        for c0, c1 in zip(edges[:-1], edges[1:]):
            x_span = np.empty(n)
            pnlss_jacobian(*args, x0.copy(), x_span, Sx, 4, J, c0, c1)
            if c0 == 0:
                x_end = x_span
            else:
                np.testing.assert_array_equal(x_span, x_end)
        return J, Sx, x_end

    whole, S_whole, x_whole = run([0, n_sx + n])
    assert np.all(np.isfinite(whole))
    for edges in ([0, 5, n_sx + n], [0, n_sx, n_sx + n], [0, n_sx + 1, n_sx + n], [0, 17, 40, n_sx + 2, n_sx + n]):
        J, S, x_end = run(edges)
        np.testing.assert_allclose(J, whole, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(S, S_whole, rtol=1e-12, atol=1e-14)
        np.testing.assert_array_equal(x_end, x_whole)
