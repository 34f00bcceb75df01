"""The verdict: the noise floor of the training data (:mod:`.noise_floor`) and
the ranking and decision on validation signals (:mod:`.decision`)."""
