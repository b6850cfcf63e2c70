"""Statistics over tracks (`railride.studies.study.StudyResult`): the mean reduction against passive of
each controller with its 5-95 % band, one panel per metric."""

from __future__ import annotations

import numpy as np

from railride.errors import InputError
from railride.plots._style import (
    PAGE_WIDTH,
    given_axes,
    grid_shape,
    new_figure,
    set_title,
    styled,
    suspension_label,
    suspension_style,
)

#: the metrics drawn by default, and their titles
DEFAULT_METRICS = {
    "acceleration_m_s2_rms": "acceleration RMS",
    "displacement_m_rms": "displacement RMS",
    "pitch_deg_rms": "pitch RMS",
    "roll_deg_rms": "roll RMS",
    "centre_N_MV_z": "N_MV,z (centre)",
}


@styled
def plot_study(result, ax=None, metrics=None):
    """One panel per metric (default `DEFAULT_METRICS`): per speed and condition (load, fault,
    delay) a group, per controller a marker at the mean reduction [%] against passive, with a bar
    from the 5th to the 95th percentile over the study's tracks (speeds and loads are never
    pooled). ``ax``: one Axes per metric, or None for a new figure (at most three panels a
    row). Returns the figure."""
    summary = result.summary
    metrics = list(DEFAULT_METRICS) if metrics is None else list(metrics)
    unknown = [m for m in metrics if m not in set(summary["metric"])]
    if unknown:
        raise InputError(f"metrics: {unknown[0]!r} is not a metric of the study; allowed {', '.join(DEFAULT_METRICS)}")
    controlled = [n for n in dict.fromkeys(summary["controller"]) if n != "passive"]
    part = summary[summary["controller"] != "passive"]
    conditions = list(
        dict.fromkeys(zip(part["speed_m_s"], part["load"], part["stiffness"], part["fault"], part["delay"]))
    )
    spare = None  # a free panel of the grid, where the legend covers no data
    if ax is None:
        n_rows, columns = grid_shape(len(metrics), 3)
        upright = len(conditions) * columns > 9  # as `crowded` below: room for the upright labels
        fig = new_figure((PAGE_WIDTH, 0.8 + (2.6 + (1.4 if upright else 0.0)) * n_rows))
        axes = fig.subplots(n_rows, columns, squeeze=False).ravel()
        for a in axes[len(metrics) :]:
            a.set_visible(False)
        spare = axes[len(metrics)] if len(axes) > len(metrics) else None
        axes = axes[: len(metrics)]
    else:
        axes = given_axes(ax, len(metrics), f"one per metric: {', '.join(metrics)}")
        fig = axes[0].figure
        columns = len(metrics)
    width = 0.8 / max(1, len(controlled))
    x = np.arange(len(conditions))
    crowded = len(conditions) * columns > 9  # "load x1.3" side by side ran into each other
    for a, metric in zip(axes, metrics):
        rows = part[part["metric"] == metric].set_index(
            ["controller", "speed_m_s", "load", "stiffness", "fault", "delay"]
        )
        for k, name in enumerate(controlled):
            mean = np.array([rows.loc[(name, *c), "reduction_mean"] for c in conditions], dtype=float)
            lo = np.array([rows.loc[(name, *c), "reduction_p5"] for c in conditions], dtype=float)
            hi = np.array([rows.loc[(name, *c), "reduction_p95"] for c in conditions], dtype=float)
            pos = x - 0.4 + width * (k + 0.5)
            colour = suspension_style(name).get("color", f"C{k}")
            a.errorbar(
                pos,
                mean,
                yerr=[mean - lo, hi - mean],
                fmt="o",
                color=colour,
                capsize=3,
                markersize=4,
                label=suspension_label(name),
            )
        a.axhline(0.0, color="k", linewidth=0.8)
        labels = [_condition_label(*c, crowded) for c in conditions]
        # crowded: each condition on one line, turned upright, so that neighbours cannot overlap
        a.set_xticks(x, labels, fontsize="small", rotation=90 if crowded else 0)
        a.set_title(DEFAULT_METRICS.get(metric, metric))
        a.grid(False, axis="x")
    for k, a in enumerate(axes):
        if k % columns == 0:
            a.set_ylabel("reduction against passive (%)\nmean, 5-95 % band")
    if spare is not None:
        spare.set_visible(True)
        spare.axis("off")
        spare.legend(*axes[0].get_legend_handles_labels(), loc="center", fontsize="small")
    elif ax is None:
        fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=3, fontsize="small")
    else:
        axes[0].legend(fontsize="small")
    if ax is None:
        s = result.settings
        seeds = s.get("track_seeds") or []  # None: a scenario that is not a random track
        over = f"{len(seeds)} track seeds" if seeds else "one run"
        set_title(fig, f"{s.get('scenario')}: {over} per speed and condition")
    return fig


def _condition_label(speed: float, load: float, stiffness: float, fault: str, delay: int, crowded: bool = False) -> str:
    parts = [
        f"{speed:g} m/s",
        f"load x{load:g}",
        *([] if stiffness == 1.0 else [f"k_sz x {stiffness:g}"]),
        *([] if fault == "none" else [fault]),
        *([] if delay == 1 else [f"delay {delay}"]),
    ]
    return (", " if crowded else "\n").join(parts)
