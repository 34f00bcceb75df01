"""The diagnosis of a structure of several degrees of freedom: the spectra
of periodic records (:mod:`.spectra`), the force laws a connection is tried
with (:mod:`.laws`), the locator that fits every place and law without
simulating (:mod:`.locator`), a modal nominal's recalibration and
corrections (:mod:`.recalibrate`), a lumped nominal's update and
corrections of its masses, springs and damping (:mod:`.update`), the fit
of a connection by simulation (:mod:`.refine`) and the diagnosis itself
(:mod:`.diagnosis`)."""
