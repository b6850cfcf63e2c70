"""The league table as a bar chart: mean RMS reduction per controller and response, with the
same gains on the ideal actuator drawn as an outline beside each bar (a reference, not a bound)."""

from __future__ import annotations

import numpy as np

from railride.errors import InputError
from railride.plots._style import (
    COLUMN_WIDTH,
    PAGE_WIDTH,
    fit_text,
    given_axes,
    new_figure,
    styled,
    suspension_label,
    suspension_style,
)

_RESPONSES = (
    ("acceleration_m_s2", "acceleration"),
    ("displacement_m", "displacement"),
    ("pitch_deg", "pitch"),
    ("roll_deg", "roll"),
)
#: the markers of the load factors in `plot_league_comfort`
_MARKERS = ("o", "s", "^", "D", "v", "P", "X")


@styled
def plot_league(table, ax=None):
    """Bars of the mean RMS reduction [%] of each response (groups) per controller (bars),
    outlines at the ideal actuator's mean reduction with the same gains. ``table``: a
    `railride.studies.league.LeagueTable`. Returns the figure."""
    summary = table.summary
    controlled = [n for n in table.controllers if n != "passive"]
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 3.2))
        ax = fig.add_subplot()
    else:
        ax = given_axes(ax, 1, "the reductions")[0]
        fig = ax.figure
    width = 0.8 / max(1, len(controlled))
    x = np.arange(len(_RESPONSES))
    for k, name in enumerate(controlled):
        mr = [summary.loc[name].get(f"{r}_reduction_percent", np.nan) for r, _ in _RESPONSES]
        ideal = [summary.loc[name].get(f"{r}_ideal_reduction_percent", np.nan) for r, _ in _RESPONSES]
        pos = x - 0.4 + width * (k + 0.5)
        colour = suspension_style(name).get("color", f"C{k}")
        ax.bar(pos, mr, width * 0.9, color=colour, label=suspension_label(name))
        ax.bar(pos, ideal, width * 0.9, fill=False, edgecolor=colour, linestyle="--")
    ax.axhline(0.0, color="k", linewidth=0.8)
    ax.set_xticks(x, [label for _, label in _RESPONSES])
    ax.set_ylabel("RMS reduction against passive (%)")
    n_cases = int(summary["cases"].max()) if len(summary) else 0
    loads = list(dict.fromkeys(table.cases["load"])) if "load" in table.cases else []
    pooled = f", loads {', '.join(f'{x:g}' for x in loads)} pooled" if len(loads) > 1 else ""
    ax.set_title(f"Mean over {n_cases} case{'s' if n_cases != 1 else ''}{pooled}; dashed outline: ideal actuator")
    ax.grid(False, axis="x")
    ax.legend(ncols=2)
    return fig


@styled
def plot_league_comfort(table, ax=None, *, index: str = "N_MV_z"):
    """Ride comfort at the carbody centre against speed, one line per controller (and per load
    factor where the league ran several: the loads are never pooled): ``index`` N_MV_z
    (EN 12299, vertical part) or aw_Wk (ISO 2631-1 a_w, m/s^2), the mean over the scenarios and
    track seeds at each speed. ``table``: a `railride.studies.league.LeagueTable`."""
    column = f"centre_{index}"
    if column not in table.cases:
        raise InputError(f"index = {index!r}: the league table has no {column} (allowed N_MV_z, aw_Wk)")
    if ax is None:
        fig = new_figure((COLUMN_WIDTH, 3.0))
        ax = fig.add_subplot()
    else:
        ax = given_axes(ax, 1, "the comfort index")[0]
        fig = ax.figure
    cases = table.cases if "load" in table.cases else table.cases.assign(load=1.0)
    loads = list(dict.fromkeys(cases["load"]))
    mean = cases.groupby(["controller", "load", "speed_m_s"])[column].mean()  # each line in order of speed
    for name in table.controllers:
        for k, load in enumerate(loads):
            line = mean.loc[(name, load)]
            style = suspension_style(name)
            label = suspension_label(name)
            if len(loads) > 1:  # one line per load, told apart by its marker
                style, label = {**style, "marker": _MARKERS[k % len(_MARKERS)]}, f"{label}, load {load:g}"
            ax.plot(line.index, line.values, **{"marker": "o", **style}, label=label)
    ax.set_xlabel("speed (m/s)")
    ax.set_ylabel("N$_{MV,z}$ (carbody centre)" if index == "N_MV_z" else "a$_w$ Wk (m/s$^2$, carbody centre)")
    ax.set_title(fit_text(f"Mean over {', '.join(table.settings.get('scenarios', []))}", COLUMN_WIDTH - 0.6, 9.0))
    ax.legend(fontsize="small")
    return fig
