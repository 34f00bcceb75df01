"""The diagnosis of a structure of several degrees of freedom: the spectra
of periodic records (:mod:`.spectra`), the force laws a connection is tried
with (:mod:`.laws`), the locator that fits every place and law without
simulating (:mod:`.locator`), the nominal's modal corrections
(:mod:`.recalibrate`), the update of a lumped nominal's masses, springs and
damping (:mod:`.update`), the fit of a connection by simulation
(:mod:`.refine`) and the diagnosis itself (:mod:`.diagnosis`)."""
