"""The initial state of a record that does not start from rest, read off its
first measured outputs.

A record cut from a longer run (the test part of a benchmark, a measurement
started while the structure was moving) starts in a state the model does not
know. Simulated from rest, its first samples carry a transient the system
never showed, as long as the model's slowest pole. The field's benchmarks
allow the first samples of a test record (its state-initialisation window)
to be used for that state and leave them out of the score. The state is the
one whose simulation reproduces the window's outputs best in least squares:
exact in one Gauss-Newton step for a linear model, a few steps for a
nonlinear one.
"""
import numpy as np

from .model_base import DivergenceError

__all__ = ["estimate_initial_state"]

# Gauss-Newton on the state: steps at most, halvings of a step that does not
# lower the misfit, and the relative decrease below which it stops.
_MAX_STEPS = 20
_MAX_HALVINGS = 12
_RTOL = 1e-10


def _window_misfit(model, U_head, Y_head, x0):
    try:
        return (model.simulate(U_head, x0)[0] - Y_head).ravel()
    except DivergenceError:
        return None


def _state_jacobian(model, U_head, Y_head, x0, residual):
    """Forward differences of the window's residual by each state (one short
    simulation per state: the window is a few dozen samples)."""
    n = x0.size
    jac = np.empty((residual.size, n))
    for j in range(n):
        step = 1e-6 * max(1.0, abs(x0[j]))
        shifted = x0.copy()
        shifted[j] += step
        moved = _window_misfit(model, U_head, Y_head, shifted)
        if moved is None:
            return None
        jac[:, j] = (moved - residual) / step
    return jac


def estimate_initial_state(model, U, Y_head):
    """The state at the first sample of ``U`` that best reproduces the
    measured outputs ``Y_head`` over the first ``len(Y_head)`` samples.

    Parameters
    ----------
    model : StateSpaceModel
        The model, in the units of ``U`` and ``Y_head``.
    U : ndarray of shape (n_samples, n_inputs)
    Y_head : ndarray of shape (n_window, n_outputs)
        Outputs measured over the first ``n_window <= n_samples`` samples.

    Returns
    -------
    x0 : ndarray of shape (n_states,)
        Least-squares estimate (minimum norm where the window cannot tell
        some states apart); zero if no state simulates the window.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.statespace.pnlss import PNLSSModel
    >>> model = PNLSSModel(A=np.array([[0.9]]), B=np.array([[1.0]]), C=np.array([[1.0]]),
    ...                    D=np.zeros((1, 1)), E=np.zeros((1, 0)), F=np.zeros((1, 0)),
    ...                    exE=np.zeros((0, 2), dtype=int), exF=np.zeros((0, 2), dtype=int))
    >>> U = np.ones((30, 1))
    >>> Y = model.simulate(U, np.array([5.0]))[0]
    >>> estimate_initial_state(model, U, Y[:10]).round(8).tolist()
    [5.0]
    """
    n_window = Y_head.shape[0]
    U_head = np.ascontiguousarray(U[:n_window])
    x0 = np.zeros(model.n_states)
    residual = _window_misfit(model, U_head, Y_head, x0)
    if residual is None:
        return x0
    cost = residual @ residual
    for _ in range(_MAX_STEPS):
        jac = _state_jacobian(model, U_head, Y_head, x0, residual)
        if jac is None:
            break
        step = np.linalg.lstsq(jac, -residual, rcond=1e-10)[0]
        for _ in range(_MAX_HALVINGS):
            trial = _window_misfit(model, U_head, Y_head, x0 + step)
            if trial is not None and trial @ trial < cost:
                break
            step = step / 2
        else:
            break
        x0, residual, previous, cost = x0 + step, trial, cost, trial @ trial
        if previous - cost <= _RTOL * previous:
            break
    return x0
