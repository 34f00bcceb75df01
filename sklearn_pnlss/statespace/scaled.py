"""A fitted nonlinear state-space model in the user's units.

Models are fitted on normalised signals (unit-rms inputs, outputs and
states), where high-degree monomials stay well conditioned. A
:class:`ScaledModel` keeps that normalised model together with the scales
that bring it back to the user's units: it simulates user-unit signals and
gives itself in user units. The estimators expose it as ``model_``; users
import the class as ``sklearn_pnlss.ScaledModel``.
"""
from dataclasses import dataclass, replace

import numpy as np

from .initial_state import estimate_initial_state
from .linear import simulate_linear_signal
from .model_base import StateSpaceModel
from .pnlss import PNLSSModel

__all__ = ["ScaledModel", "linear_scaled_model", "normalised_linear_start", "unit_rms_scales"]


def unit_rms_scales(signals):
    """rms of each channel over the signals (N_i, k), 1 where it is zero
    (a silent channel has nothing to normalise)."""
    scale = np.sqrt(np.mean(np.concatenate(signals) ** 2, axis=0))
    scale[scale == 0] = 1.0
    return scale


@dataclass
class ScaledModel:
    """A state-space model of normalised signals with the scales of its
    inputs, outputs and states.

    ``u = input_offset + input_scale * u_n``, ``y = output_offset +
    output_scale * y_n`` and ``x = state_scale * x_n``, where ``u_n, y_n,
    x_n`` are the variables of ``normalised``. The offsets are an operating
    point (a pump's mean voltage and the water level it holds, a sensor's
    zero): the model describes the deviations from it, and its rest is
    there.

    What a fitted estimator's ``model_`` is. :meth:`in_user_units` gives the
    model itself in the user's units: a ``PNLSSModel`` (fields ``A, B, C,
    D, E, F``, the monomial exponents ``exE, exF`` over ``[x; u]`` and the
    trusted box ``bounds``) or a ``DecoupledModel`` (``A, B, C, D, Wx, Wy,
    V``, the branch coefficients ``G`` of ``z**1 .. z**d`` and the branch
    inputs' trusted ranges ``bounds``), with ``simulate(U, x0)`` and
    ``simulate_states(U, x0)``.

    Parameters
    ----------
    normalised : PNLSSModel or DecoupledModel
        The model in normalised units (what Levenberg-Marquardt fits).
    input_scale : ndarray of shape (n_inputs,)
    output_scale : ndarray of shape (n_outputs,)
    state_scale : ndarray of shape (n_states,)
    input_offset : ndarray of shape (n_inputs,) or None, default=None
        None: zero.
    output_offset : ndarray of shape (n_outputs,) or None, default=None
        None: zero.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn_pnlss.statespace.pnlss import PNLSSModel
    >>> from sklearn_pnlss import ScaledModel
    >>> ex = np.array([[2, 0]])  # x**2
    >>> unit = PNLSSModel(A=np.array([[0.5]]), B=np.array([[1.0]]), C=np.array([[1.0]]),
    ...                   D=np.array([[0.0]]), E=np.array([[0.1]]), F=np.zeros((1, 0)),
    ...                   exE=ex, exF=np.zeros((0, 2), dtype=int))
    >>> model = ScaledModel(unit, input_scale=np.array([2.0]), output_scale=np.array([3.0]),
    ...                     state_scale=np.array([5.0]))
    >>> U = np.array([[2.0], [4.0], [0.0]])
    >>> # x_n: 0, 1, 0.5 + 2 + 0.1 = 2.6; y = 3 x_n
    >>> model.simulate(U).ravel().round(12).tolist()
    [0.0, 3.0, 7.8]
    >>> np.allclose(model.in_user_units().simulate(U)[0], model.simulate(U))
    True
    """

    normalised: StateSpaceModel
    input_scale: np.ndarray
    output_scale: np.ndarray
    state_scale: np.ndarray
    input_offset: np.ndarray | None = None
    output_offset: np.ndarray | None = None

    def __post_init__(self):
        if self.input_offset is None:
            self.input_offset = np.zeros_like(self.input_scale)
        if self.output_offset is None:
            self.output_offset = np.zeros_like(self.output_scale)

    @property
    def n_states(self):
        return self.normalised.n_states

    @property
    def n_params(self):
        return self.normalised.n_params

    @property
    def n_nonlinear_params(self):
        return self.normalised.n_nonlinear_params

    def with_normalised(self, normalised):
        """The same scales around another normalised model."""
        return replace(self, normalised=normalised)

    def normalise_inputs(self, U):
        """``U`` (N, m) in normalised units."""
        return (U - self.input_offset) / self.input_scale

    def normalise_outputs(self, Y):
        """``Y`` (N, p) in normalised units."""
        return (Y - self.output_offset) / self.output_scale

    def user_outputs(self, Y_n):
        """Normalised outputs ``Y_n`` (N, p) in the user's units."""
        return Y_n * self.output_scale + self.output_offset

    def simulate(self, U, period=None):
        """Output (N, p) for the input ``U`` (N, m), both in the user's
        units: in periodic steady state with ``period`` (the length a
        multiple of it), else from rest. Raises
        :class:`~sklearn_pnlss.DivergenceError` when the simulation
        diverges."""
        return self.user_outputs(self.normalised.simulate_signal(self.normalise_inputs(U), period))

    def simulate_from_window(self, U, Y_head):
        """Output (N, p) for the input ``U`` (N, m), both in the user's
        units, from the state that best reproduces the measured outputs
        ``Y_head`` over the first ``len(Y_head)`` samples (see
        :func:`~sklearn_pnlss.statespace.initial_state.estimate_initial_state`).
        Raises :class:`~sklearn_pnlss.DivergenceError` when the simulation
        diverges."""
        U_n = self.normalise_inputs(U)
        x0 = estimate_initial_state(self.normalised, U_n, self.normalise_outputs(Y_head))
        return self.user_outputs(self.normalised.simulate(U_n, x0)[0])

    def states_inputs(self, U, period=None):
        """``[x; u]`` (N, n + m) in the user's units along the simulation of
        ``U`` (periodic steady state for a signal of whole periods)."""
        s = self.normalised.states_inputs(self.normalise_inputs(U), period)
        return s * np.concatenate([self.state_scale, self.input_scale]) + np.concatenate(
            [np.zeros(self.n_states), self.input_offset])

    def normalised_trajectory(self, U_list, period=None):
        """``[x_n; u_n]`` in normalised units along the simulation of the
        user-unit inputs ``U_list``, stacked (periodic steady state for
        signals of whole periods): where the normalised model's
        nonlinearity is evaluated."""
        return self.normalised.trajectory([self.normalise_inputs(U) for U in U_list], period)

    def range_excursion(self, U, period=None):
        """How far the simulation of ``U`` takes the nonlinearity past its
        trusted range (see
        :meth:`~sklearn_pnlss.statespace.model_base.StateSpaceModel.range_excursion`)."""
        return self.normalised.range_excursion(self.normalise_inputs(U), period)

    def in_user_units(self):
        """The model itself in the user's units (a model of the same class,
        which simulates user-unit signals directly; with offsets, the
        deviations of the signals from them)."""
        return self.normalised.rescaled(self.state_scale, self.input_scale, self.output_scale)


def normalised_linear_start(A, B, C, D, X_list, y_list, periods, input_offset=None, output_offset=None):
    """The linear model ``A, B, C, D`` (user units) normalised to unit-rms
    inputs, outputs and states on the training signals: where the nonlinear
    fits start, since high-degree terms of order-one variables stay well
    conditioned.

    ``periods`` gives, per signal of ``X_list``, its period when it is
    periodic steady state (else None): the states' rms is read off the
    linear model's simulation of it. Returns a :class:`ScaledModel` of a
    polynomial model without monomials. ``A, B, C, D`` map the deviations
    of the signals from the offsets (None: zero), which the start keeps.
    """
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    input_offset = np.zeros(m) if input_offset is None else np.asarray(input_offset, float)
    output_offset = np.zeros(p) if output_offset is None else np.asarray(output_offset, float)
    X_list = [U - input_offset for U in X_list]
    y_list = [Y - output_offset for Y in y_list]
    if np.any(np.all(np.concatenate(X_list) == 0, axis=0)):
        raise ValueError("An input of X is identically zero: no excitation to identify a model from.")
    # Output the states themselves (C = I, D = 0) to measure their rms.
    states = [simulate_linear_signal(A, B, np.eye(n), np.zeros((n, m)), U, periodic_with=per)
              for U, per in zip(X_list, periods)]
    u_scale, y_scale, x_scale = unit_rms_scales(X_list), unit_rms_scales(y_list), unit_rms_scales(states)
    T, Ti = np.diag(x_scale), np.diag(1 / x_scale)
    Su, Sy_i = np.diag(u_scale), np.diag(1 / y_scale)
    linear = linear_scaled_model(Ti @ A @ T, Ti @ B @ Su, Sy_i @ C @ T, Sy_i @ D @ Su)
    return ScaledModel(linear.normalised, u_scale, y_scale, x_scale, input_offset, output_offset)


def linear_scaled_model(A, B, C, D, input_offset=None, output_offset=None):
    """A linear model ``A, B, C, D`` as a :class:`ScaledModel` (a
    polynomial model without monomials, unit scales; ``A, B, C, D`` map
    the deviations from the offsets, None: zero)."""
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    linear = PNLSSModel(A=A, B=B, C=C, D=D, E=np.zeros((n, 0)), F=np.zeros((p, 0)),
                        exE=np.zeros((0, n + m), dtype=np.int64), exF=np.zeros((0, n + m), dtype=np.int64))
    return ScaledModel(linear, np.ones(m), np.ones(p), np.ones(n), input_offset, output_offset)
