"""railride's figures: one module per result type, each plot function drawing into the
``ax`` it is given (one Axes, or a sequence of Axes for a figure of several panels) or, when
``ax`` is None, into a new figure, and returning the matplotlib Figure.

* `railride.plots.ride`: the carbody responses of a ride result;
* `railride.plots.comparison`: a controller comparison (responses, damper forces, voltages,
  acceleration spectra);
* `railride.plots.rig`: the damper rig (hysteresis cycles, force tracking);
* `railride.plots.tuning`: the sensitivity curves of a tuning study;
* `railride.plots.sweep`: a sweep's RMS and comfort against its swept axis;
* `railride.plots.frf`: the carbody frequency responses, magnitude and phase;
* `railride.plots.pareto`: the Pareto view of a controller's gains;
* `railride.plots.league`, `railride.plots.study`, `railride.plots.optimise`: the league
  table, the statistics over tracks, the global optimiser.

New figures are built on matplotlib's object API with the Agg canvas: nothing here touches
pyplot's global figure list or the user's backend, so no window ever opens and figures do not
pile up in memory. Every new figure is drawn in one house style (`STYLE`: sizes for a journal
column or page, `COLUMN_WIDTH` and `PAGE_WIDTH`) inside ``matplotlib.rc_context``, so the
global settings stay as they were. `save_figure` writes a figure as PNG, PDF or SVG;
`FigureOptions` is what a result's ``save(folder, figure_formats=, dpi=)`` writes.
"""

from railride.plots._style import (
    COLUMN_WIDTH,
    FIGURE_FORMATS,
    MAX_DPI,
    MIN_DPI,
    PAGE_WIDTH,
    PNG_DPI,
    STYLE,
    FigureOptions,
    new_figure,
    save_figure,
    save_png,
)

__all__ = [
    "COLUMN_WIDTH",
    "FIGURE_FORMATS",
    "MAX_DPI",
    "MIN_DPI",
    "PAGE_WIDTH",
    "PNG_DPI",
    "STYLE",
    "FigureOptions",
    "new_figure",
    "save_figure",
    "save_png",
]
