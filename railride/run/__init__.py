"""A run of the vehicle: solver settings, the simulation, its result, and the damper rig."""
