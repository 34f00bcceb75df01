"""Candidate effects and the starts read from the data: what each adds to the nominal simulator
(:mod:`.effects`), what the training data say before any fit (:mod:`.clues`,
:mod:`.stiffness_start`)."""
