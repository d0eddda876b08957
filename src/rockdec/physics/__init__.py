"""The rocking block and what drives it: the models (paper eqs. 1-6), the load and sensor
(the record model), the simulators (eqs. 21-24) and the run contract that fixes a series."""
