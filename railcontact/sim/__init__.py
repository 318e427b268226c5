"""Simulation on top of the contact: the wheelset model (:mod:`.dynamics`), its co-simulation
with the FMU through fmpy (:mod:`.cosim`) and ``railcontact demo`` (:mod:`.demo`); a bogie
vehicle (:mod:`.vehicle`, parameters :mod:`.vehicle_data`) with its contact interface
(:mod:`.vehicle_contact`), its linearised contact (:mod:`.linear_contact`) and linear
stability (:mod:`.stability`), and ``railcontact demo --vehicle`` (:mod:`.vehicle_demo`)."""
