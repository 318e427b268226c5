"""Simulation on top of the FMU: the wheelset model (:mod:`.dynamics`), its co-simulation
with the FMU through fmpy (:mod:`.cosim`) and ``railcontact demo`` (:mod:`.demo`)."""
