"""Nonparametric frequency-domain estimates behind the estimators: the best
linear approximation and its noise and nonlinear distortion levels.

Internal: not part of the API; may change without notice (the estimators in
:mod:`sklearn_pnlss` are the way in).
"""
