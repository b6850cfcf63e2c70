"""What every railride plot shares: the new figure, the PNG file, and the name and line style
of each suspension."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._io import atomic_write

#: resolution of the saved figures [dots per inch]
PNG_DPI = 120
#: line style and colour per suspension, as in the paper's Figs. 8-11 (passive dash-dot, PID
#: dotted, SAS (attitude) dashed, SAS (attitude+ride) solid); "mr" is a sweep's MR damper at a
#: constant voltage
SUSPENSION_STYLES = {
    "passive": {"linestyle": "-.", "color": "0.25"},
    "pid": {"linestyle": ":", "color": "tab:blue"},
    "sas-attitude": {"linestyle": "--", "color": "tab:orange"},
    "sas-attitude-ride": {"linestyle": "-", "color": "tab:red"},
    "mr": {"linestyle": "-", "color": "tab:green"},
    # the laws beyond the paper
    "skyhook": {"linestyle": "-", "color": "tab:purple"},
    "skyhook-on-off": {"linestyle": "--", "color": "tab:purple"},
    "groundhook": {"linestyle": "-", "color": "tab:brown"},
    "hybrid": {"linestyle": "-", "color": "tab:pink"},
    "clipped-optimal": {"linestyle": "-", "color": "tab:cyan"},
    "passive-on": {"linestyle": ":", "color": "0.45"},
    "passive-off": {"linestyle": ":", "color": "0.65"},
}


def new_figure(figsize):
    """A constrained-layout Figure of ``figsize`` (inches) on its own Agg canvas, never
    registered with pyplot."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_png(fig, path) -> None:
    """Write ``fig`` to ``path`` as PNG, atomically (a reader never sees a half-written file);
    nothing when ``path`` is None."""
    if path is not None:
        atomic_write(Path(path), lambda tmp: fig.savefig(tmp, format="png", dpi=PNG_DPI))


def given_axes(ax, count: int, what: str) -> list:
    """The ``count`` Axes of ``ax`` (one Axes or a sequence, any shape) in order; ValueError
    naming what each panel is when the count differs."""
    axes = list(np.ravel(ax))
    if len(axes) != count:
        raise ValueError(f"ax: {count} Axes ({what}), got {len(axes)}")
    return axes


def suspension_label(name: str) -> str:
    """The display name of a suspension: "Passive", "PID", "SAS (attitude)", ...,
    "MR (constant voltage)"; an unknown name as it is."""
    from ..control import LABELS  # here, not above: control pulls in the vehicle model

    if name == "mr":
        return "MR (constant voltage)"
    return LABELS.get(name, name)


def suspension_style(name: str) -> dict:
    """The line style of `SUSPENSION_STYLES` for ``name``; a plain solid line for another."""
    return SUSPENSION_STYLES.get(name, {"linestyle": "-"})
