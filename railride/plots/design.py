"""A design study (`railride.studies.design_result.DesignResult`): each law's RMS ratios to
passive against speed on held-out track, with the 5-95 % band over the held-out runs, one
panel per response and one line style per load."""

from __future__ import annotations

import numpy as np

from railride.plots._style import (
    PAGE_WIDTH,
    given_axes,
    new_figure,
    set_title,
    styled,
    suspension_label,
    suspension_style,
)

#: the responses drawn, by their run-table column, and their titles
PANELS = {
    "acceleration_m_s2_rms": "acceleration RMS",
    "displacement_m_rms": "displacement RMS",
    "pitch_deg_rms": "pitch RMS",
    "roll_deg_rms": "roll RMS",
}
#: the line style of each load factor, in the order given
LOAD_STYLES = ("-", "--", ":", "-.")


@styled
def plot_design(result, ax=None):
    """Four panels (`PANELS`): per law and load, the mean RMS ratio to passive over the held-out
    runs against speed, with a band from the 5th to the 95th percentile; passive at 1. ``ax``:
    four Axes, or None for a new figure. Returns the figure."""
    summary = result.summary
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 5.6))
        axes = list(fig.subplots(2, 2).ravel())
    else:
        axes = given_axes(ax, len(PANELS), f"one per response: {', '.join(PANELS)}")
        fig = axes[0].figure
    laws = [n for n in dict.fromkeys(summary["controller"]) if n != "passive"]
    loads = list(dict.fromkeys(summary["load"]))
    for a, (metric, title) in zip(axes, PANELS.items()):
        part = summary[summary["metric"] == metric]
        for k, name in enumerate(laws):
            colour = suspension_style(name).get("color", f"C{k}")
            for j, load in enumerate(loads):
                rows = part[(part["controller"] == name) & (part["load"] == load)].sort_values("speed_m_s")
                v = rows["speed_m_s"].to_numpy(dtype=float)
                mean = rows["ratio_mean"].to_numpy(dtype=float)
                label = suspension_label(name) + (f", load {load:g}" if len(loads) > 1 else "")
                a.plot(v, mean, LOAD_STYLES[j % len(LOAD_STYLES)], color=colour, marker="o", markersize=3, label=label)
                lo, hi = rows["ratio_p5"].to_numpy(dtype=float), rows["ratio_p95"].to_numpy(dtype=float)
                if np.isfinite(lo).any() and len(v) > 1:
                    a.fill_between(v, lo, hi, color=colour, alpha=0.12, linewidth=0)
                elif np.isfinite(lo).any():  # one speed: a band has no width, so a bar
                    a.errorbar(v, mean, yerr=[mean - lo, hi - mean], color=colour, capsize=3, linewidth=1)
        a.axhline(1.0, color="k", linewidth=0.8, label="passive")
        a.set_title(title)
        a.set_xlabel("speed (m/s)")
    axes[0].set_ylabel("RMS / passive, held out\nmean, 5-95 % band")
    if len(axes) > 2:
        axes[2].set_ylabel("RMS / passive, held out\nmean, 5-95 % band")
    if ax is None:
        fig.legend(*axes[0].get_legend_handles_labels(), loc="outside lower center", ncols=3, fontsize="small")
        s = result.settings
        set_title(
            fig,
            f"Design on held-out track: {', '.join(s.get('tracks', []))}, "
            f"seeds {', '.join(map(str, s.get('test_seeds', [])))}; vehicle {s.get('vehicle', {}).get('name')}",
        )
    else:
        axes[0].legend(fontsize="small")
    return fig


@styled
def plot_design_costs(result, ax=None):
    """What each law costs against what it gives, on held-out track: per law and speed/load
    point, its score there (the design's objective of its mean ratios to passive; lower is
    better) against the RMS damper force it asks for (mean over the held-out runs), passive's
    viscous dampers beside them at passive's own score (1 for minimax). One line per law
    through its points, in order of speed (a law's force need not grow with speed, so a line
    may turn back); the leading law's points are named by speed (and load, with several).
    ``ax``: one Axes, or None for a new figure. Returns the figure."""
    summary = result.summary
    if ax is None:
        fig = new_figure((PAGE_WIDTH * 0.6, 4.2))
        a = fig.subplots()
    else:
        (a,) = given_axes(ax, 1, "the score against the damper force")
        fig = a.figure
    force = summary[summary["metric"] == "force_rms_n"].set_index(["controller", "speed_m_s", "load"])["mean"]
    baseline = result.tuning.objective.passive_score
    for k, point in enumerate(result.points):
        v, load = point["speed_m_s"], point["load"]
        if ("passive", v, load) in force.index:
            label = "passive" if k == 0 else None
            a.plot(force[("passive", v, load)] / 1e3, baseline, "ks", markersize=4, label=label)
    for j, row in enumerate(result.ranking):
        name = row["controller"]
        colour = suspension_style(name).get("color", f"C{j}")
        xs, ys, drawn = [], [], []
        for point in result.points:
            key = (name, point["speed_m_s"], point["load"])
            score = point["scores"].get(name)
            if key in force.index and score is not None and np.isfinite(score):
                xs.append(force[key] / 1e3)
                ys.append(score)
                drawn.append(point)
        if xs:
            a.plot(xs, ys, "-o", color=colour, markersize=3, linewidth=0.8, label=suspension_label(name))
        if j == 0:  # the leading law's points named by speed (and load): which point is which
            several = len({p["load"] for p in result.points}) > 1
            for x, y, point in zip(xs, ys, drawn):
                text = f"{point['speed_m_s']:g} m/s" + (f", {point['load']:g}" if several else "")
                a.annotate(text, (x, y), textcoords="offset points", xytext=(4, 3), fontsize="x-small", color=colour)
    a.axhline(baseline, color="k", linewidth=0.6, linestyle=":")
    a.set_xlabel("RMS damper force, held-out mean (kN)")
    a.set_ylabel("score at each speed and load\n(lower is better)")
    a.legend(fontsize="small")
    if ax is None:
        set_title(fig, "What each law gives against what it asks of its dampers, held out")
    return fig
