"""The secondary suspension: damper models, control laws, sensing, faults and the `Suspension`
value that carries them to a run."""
