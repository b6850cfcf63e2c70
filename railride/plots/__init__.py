"""railride's figures: one module per result type, each plot function drawing into the
``ax`` it is given (one Axes, or a sequence of Axes for a figure of several panels) or, when
``ax`` is None, into a new figure, and returning the matplotlib Figure.

* `railride.plots.ride`: the carbody responses of a ride result;
* `railride.plots.comparison`: a controller comparison (responses, damper forces, voltages,
  acceleration spectra);
* `railride.plots.rig`: the damper rig (hysteresis cycles, force tracking);
* `railride.plots.tuning`: the sensitivity curves of a tuning study;
* `railride.plots.sweep`: a sweep's RMS and comfort against its swept axis;
* `railride.plots.frf`: the carbody frequency responses;
* `railride.plots.pareto`: the Pareto view of a controller's gains.

New figures are built on matplotlib's object API with the Agg canvas: nothing here touches
pyplot's global figure list or the user's backend, so no window ever opens and figures do not
pile up in memory. `save_png` writes a figure as the output folders hold it.
"""

from ._style import new_figure, save_png

__all__ = ["new_figure", "save_png"]
