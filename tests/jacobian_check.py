"""Central finite differences of a model's residual: what the exact
Jacobians of the compiled kernels are checked against."""
import numpy as np


def finite_difference_jacobian(model, segments, step=1e-6):
    """d residual / d theta of ``model`` on ``segments``, column by column."""
    theta = model.theta
    J = np.empty((model.residual(segments).size, theta.size))
    for q in range(theta.size):
        d = np.zeros_like(theta)
        d[q] = step
        J[:, q] = (model.with_theta(theta + d).residual(segments)
                   - model.with_theta(theta - d).residual(segments)) / (2 * step)
    return J
