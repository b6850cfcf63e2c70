"""Test helpers shipped with the package: the plain NumPy reference of the vehicle and dampers
(the oracle of the compiled engine), kept out of the runtime modules."""
