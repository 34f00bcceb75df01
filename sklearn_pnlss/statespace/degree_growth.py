"""Fitting a PNLSS model's degrees in stages.

High-degree terms grown from a model that already captures the main
nonlinearity, one degree per stage with zero coefficients, instead of from
the linear start, where Levenberg-Marquardt's first large steps can lead
through models that fit the training signals but diverge beyond their
range (measured in :class:`~sklearn_pnlss.PNLSSRegressor`'s
``grow_degrees``).
"""
import numpy as np

from .fitting import LMFit, optimise
from .pnlss import PNLSSModel

__all__ = ["chain_stages", "degree_stages", "optimise_growing_degrees", "with_degrees"]


def degree_stages(degrees, grow):
    """The degrees fitted at each stage.

    Parameters
    ----------
    degrees : sorted list of int (all >= 2; empty: the linear model alone)
    grow : bool or "auto"
        False: one stage with all degrees. True: the lowest degree alone
        first, then one more per stage. "auto": the degrees up to 3
        together first, then one more per stage.

    Examples
    --------
    >>> degree_stages([2, 3, 5, 7], "auto")
    [(2, 3), (2, 3, 5), (2, 3, 5, 7)]
    >>> degree_stages([2, 3], True)
    [(2,), (2, 3)]
    >>> degree_stages([], "auto")
    [()]
    """
    if grow is False or not degrees:
        return [tuple(degrees)]
    # "auto" fits degrees up to 3 together: degree 2 alone, an even
    # nonlinearity, leads the fit of (2, 3) to a worse optimum.
    n_first = max(sum(d <= 3 for d in degrees), 1) if grow == "auto" else 1
    return [tuple(degrees[:k]) for k in range(n_first, len(degrees) + 1)]


def with_degrees(full, degrees, previous):
    """``full`` (a PNLSSModel, E = F = 0) restricted to the monomials of
    ``degrees``, with the linear part and coefficients of ``previous``, the
    fit on ``degrees[:-1]`` (or None). A constant term (a model around an
    operating point) belongs to every stage."""
    parts = {}
    for name, ex, coef in (("E", full.exE, full.E), ("F", full.exF, full.F)):
        degree = ex.sum(axis=1)
        keep = (degree == 0) | np.isin(degree, degrees)
        parts[name], parts["ex" + name] = np.zeros_like(coef[:, keep]), ex[keep]
        if previous is not None:
            # Both keep the full model's column order, so the held columns line up.
            held = (degree[keep] == 0) | np.isin(degree[keep], degrees[:-1])
            parts[name][:, held] = getattr(previous, name)
    linear = previous if previous is not None else full
    return PNLSSModel(A=linear.A.copy(), B=linear.B.copy(), C=linear.C.copy(), D=linear.D.copy(), **parts)


def optimise_growing_degrees(start, objectives, settings, stages, validation=None):
    """:func:`~sklearn_pnlss.statespace.fitting.optimise` stage by stage on
    growing degrees, each stage starting from the previous one's kept
    iterate.

    Parameters
    ----------
    start : ScaledModel
        Around a PNLSSModel holding every monomial of the last stage
        (coefficients zero).
    objectives : list of SimulationError
        The frequency weighting, when there is one (second objective),
        refines the last stage only.
    settings : FitSettings
        Each stage but the last runs at most ``max_iter // 2`` iterations.
    stages : list of tuple of int
        From :func:`degree_stages`.
    validation : tuple (X_list, y_list) or None

    Returns
    -------
    LMFit
        The last stage's model; iterations and validation history run on
        across the stages.
    """
    fits, previous = [], None
    for k, degrees in enumerate(stages):
        last = k == len(stages) - 1
        stage_start = start.with_normalised(with_degrees(start.normalised, degrees, previous))
        if settings.verbose and len(stages) > 1:
            print(f"degrees {degrees}", flush=True)
        fit = optimise(stage_start, objectives if last else objectives[:1], settings, validation,
                       max_iter=settings.max_iter if last else settings.max_iter // 2)
        fits.append(fit)
        previous = fit.model.normalised
    return chain_stages(fits)


def chain_stages(fits):
    """One LMFit from consecutive stages, each starting where the previous
    ended: iterations, cost and validation histories run on across the
    stages (each stage's costs are those of its last objective)."""
    if len(fits) == 1:
        return fits[0]
    last, done, best = fits[-1], fits[0].n_iter, fits[0].best_iteration
    for fit in fits[1:]:
        # Iteration 0 of a stage is the previous stage's kept iterate.
        if fit.best_iteration > 0:
            best = done + fit.best_iteration
        done += fit.n_iter
    # Each later stage's start repeats the previous stage's kept iterate.
    def joined(histories):
        return np.concatenate([histories[0]] + [h[1:] for h in histories[1:]])

    val = None
    if last.validation_history is not None:
        val = joined([f.validation_history for f in fits])
    return LMFit(
        model=last.model, n_iter=done, best_iteration=best, cost_history=joined([f.cost_history for f in fits]),
        validation_history=val, validation_error=last.validation_error,
        kept_cost=last.kept_cost, new_input_runaway=last.new_input_runaway,
    )
