"""The vehicle model: parameters and presets, plausible ranges, the vehicle matrices, its modes,
and the track (scenarios and rail inputs). Imports the engine's layout only."""
