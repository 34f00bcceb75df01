"""Fitting: simulation of the oscillator on measured inputs (:mod:`.simulate`),
the simulation-error fit of each candidate (:mod:`.calibrate`) and the
black-box yardstick (:mod:`.black_box`)."""
