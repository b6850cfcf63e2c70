# TEMPORARY re-exports: removed once every caller imports the new modules
"""The old home of the Pareto view's figure and folder: `railride.plots.pareto` and
`railride.files`."""

from .files import write_pareto_outputs as write_pareto  # noqa: F401
from .plots.pareto import plot_pareto  # noqa: F401
