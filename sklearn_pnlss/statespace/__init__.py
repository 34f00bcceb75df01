"""State-space models behind the estimators: linear tools, subspace
identification, the nonlinear models, their simulation error and
Levenberg-Marquardt.

Internal: not part of the API; may change without notice (the estimators in
:mod:`sklearn_pnlss` are the way in).
"""
