"""Newton shooting for the periodic steady state of a slowly settling structure.

Simulating period after period from rest settles a well-damped structure in
two or three periods, but a barely damped low mode, or a hysteresis whose
offset is nearly neutral, decays by a few per cent per period and would take
hundreds.  The steady state is the fixed point of the period map ``F``, which
sends the positions ``p = (y, yd, z)`` at a period's start to those at its
end: Newton's method on ``G(p) = F(p) - p`` finds it in a few periods.  The
Jacobian comes from forward differences once (one period per position) and
is then kept up to date by Broyden's rank-one updates from the periods that
are simulated anyway, so every later period is also a Newton step.  Where
the integrator gives it, the Jacobian is exact instead, from one period run
with its sensitivity recursion (one period for all positions, where
differences take one per position).  The
caller still checks each period against its start, so the answer is the
same steady state as without shooting; and a step is taken only while the
map contracts (its Jacobian's eigenvalues inside the unit circle), so that
Newton does not land on an unstable orbit the structure would never settle
on.
"""
import numpy as np

from ._newmark import STATE_Y, STATE_YD, STATE_Z

__all__ = ["PeriodShooter"]

# Forward-difference step of the period map, relative to each position's
# peak over the period: small enough for the nonlinear elements, large
# enough that round-off does not spoil a linear structure's exact step.
_FD_STEP = 1e-5


class PeriodShooter:
    """Newton (then Broyden) steps towards the fixed point of the period map.

    Parameters
    ----------
    run_period : callable
        ``run_period(state, init) -> (y, yd, z)``: simulate one period from
        ``state`` (updated in place to the end state).
    n_states : int
        Length of the integrator state.
    n_internal : int
        Internal states of the force elements.
    period_jacobian : callable, default=None
        ``period_jacobian(state, idx)``: derivatives of the positions
        ``idx`` at the period's end by those at its start (the rates
        recomputed from the equation of motion), from ``state``; None:
        forward differences.
    positions : array-like of int, default=None
        Where the positions sit in the state (default: the single
        oscillator's displacement, velocity and internal states).
    """

    def __init__(self, run_period, n_states, n_internal, period_jacobian=None, positions=None):
        self.run_period = run_period
        self.period_jacobian = period_jacobian
        self.n_states = n_states
        self.idx = (np.r_[STATE_Y, STATE_YD, STATE_Z:STATE_Z + n_internal] if positions is None
                    else np.asarray(positions, dtype=np.int64))
        self.jac = None  # Jacobian of G(p) = F(p) - p
        self.previous = None  # (p, G(p), scaled |G|) of the last step
        self.active = True

    def _state(self, p):
        s = np.zeros(self.n_states)
        s[self.idx] = p
        return s

    def _jacobian(self, p, f, scale, budget):
        """Forward-difference Jacobian of ``G`` at ``p`` (``f = F(p)``),
        steps relative to each position's peak ``scale``."""
        if self.period_jacobian is not None:
            return self.period_jacobian(self._state(p), self.idx) - np.eye(self.idx.size)
        if self.idx.size > budget:
            return None
        jac = np.empty((self.idx.size, self.idx.size))
        for j in range(self.idx.size):
            step = _FD_STEP * scale[j]
            q = p.copy()
            q[j] += step
            end = self._state(q)
            self.run_period(end, True)
            jac[:, j] = (end[self.idx] - f) / step
        return jac - np.eye(self.idx.size)

    def step(self, start, end, traces, budget):
        """The next start after a period that ran from ``start`` to ``end``.

        Returns ``(state, periods_used)``; ``state`` is None when shooting
        is off or failed, and the caller carries on from ``end``.
        """
        if not self.active:
            return None, 0
        p, f = start[self.idx], end[self.idx]
        g = f - p
        scale = np.array([max(np.max(np.abs(t)), 1e-300) for t in traces])
        size = float(np.linalg.norm(g / scale))
        used = 0
        if self.previous is not None and size > self.previous[2]:
            # The last step made things worse: the map is too nonlinear here.
            self.active = False
            return None, 0
        try:
            if self.jac is None:
                self.jac = self._jacobian(p, f, scale, budget)
                used = 1 if self.period_jacobian is not None else self.idx.size
                if self.jac is None:
                    self.active = False
                    return None, 0
            else:
                dp, dg = p - self.previous[0], g - self.previous[1]
                if dp @ dp > 0:
                    self.jac += np.outer(dg - self.jac @ dp, dp) / (dp @ dp)
            # Newton converges to any periodic orbit, also an unstable one
            # (a stiffening spring near resonance has several); the
            # structure settles only on a stable one, where the period map
            # contracts.  Otherwise plain periods find the physical orbit.
            if np.max(np.abs(np.linalg.eigvals(self.jac + np.eye(self.idx.size)))) >= 1.0:
                self.active = False
                return None, used
            p_new = p - np.linalg.solve(self.jac, g)
        except (FloatingPointError, np.linalg.LinAlgError):
            self.active = False
            return None, used
        if not np.all(np.isfinite(p_new)):
            self.active = False
            return None, used
        self.previous = (p, g, size)
        return self._state(p_new), used
