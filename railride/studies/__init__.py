"""Studies over many runs: comparison, league, cases and grids, sweeps, executors, objectives,
tuning, Pareto and the statistical study."""
