"""Helpers of the estimators: signal validation and the ``Pipeline``
hand-over.

Internal: not part of the API; may change without notice (the estimators in
:mod:`sklearn_pnlss` are the way in).
"""
