"""The application behind ``python -m sklearn_pnlss``: the Bouc-Wen study
(:mod:`.study`), its command line (:mod:`.cli`) and the sim-to-real gap demo
(:mod:`.gap_demo`).

Internal: this package is an application of the library, not part of its
API, and may change without notice. It uses only the public API; the library
never imports it.
"""
