"""The Pareto view of a controller's gains (`railride.studies.pareto.ParetoResult`): the figure
(`plot_pareto`) and its caption (`pareto_caption`), which carries the in-sample note."""

from __future__ import annotations

import numpy as np

from railride.analysis.labels import describe_scenario
from railride.plots._style import PAGE_WIDTH, given_axes, new_figure, set_title, styled, suspension_label

#: axis label of each ratio
RATIO_LABELS = {
    "acceleration": "heave acceleration at the carbody CG:\nRMS / RMS(passive)",
    "displacement": "heave displacement at the carbody CG:\nRMS / RMS(passive)",
    "pitch": "carbody pitch angle: RMS / RMS(passive)",
    "roll": "carbody roll angle: RMS / RMS(passive)",
}


def _draw_plane(a, result, x: str, y: str) -> None:
    """The samples of ``result`` in the plane of ratios ``x`` and ``y``."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    RATIOS = result.RATIOS
    ratios = result.ratios
    front = result.non_dominated
    rx, ry = ratios[:, RATIOS.index(x)], ratios[:, RATIOS.index(y)]
    plane = result.non_dominated_in(x, y)
    a.scatter(rx, ry, s=10, color="0.65", linewidths=0, label="sampled gains", zorder=2)
    a.scatter(
        rx[front], ry[front], s=16, color="tab:blue", linewidths=0, zorder=3, label="non-dominated over all four ratios"
    )
    order = np.argsort(rx[plane])
    a.step(rx[plane][order], ry[plane][order], where="post", color="tab:orange", linewidth=1.2, zorder=4)
    a.scatter(
        rx[plane],
        ry[plane],
        s=28,
        facecolors="none",
        edgecolors="tab:orange",
        zorder=4,
        label="non-dominated in this plane",
    )
    a.plot([1.0], [1.0], "x", color="k", markersize=9, markeredgewidth=2, zorder=5, label="passive (1, 1)")
    a.plot(
        [rx[0]],
        [ry[0]],
        "*",
        color="tab:red",
        markersize=14,
        markeredgecolor="k",
        markeredgewidth=0.5,
        zorder=6,
        label=f"base gains ({result.settings.get('base_gains', '?')})",
    )
    a.axhline(1.0, color="k", linewidth=0.6, linestyle=":", zorder=1)
    a.axvline(1.0, color="k", linewidth=0.6, linestyle=":", zorder=1)
    # ratios span decades when the gains do: a log scale keeps both ends readable
    a.set_xscale("log")
    a.set_yscale("log")
    for axis in (a.xaxis, a.yaxis):  # 0.2, 0.5, 1, 2: ratios read as plain numbers
        axis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
    a.set_xlabel(RATIO_LABELS[x], fontsize="small")
    a.set_ylabel(RATIO_LABELS[y], fontsize="small")


@styled
def plot_pareto(result, ax=None):
    """Two panels of `railride.studies.pareto.ParetoResult` ``result``: the acceleration ratio (x)
    against the pitch ratio, and against the roll ratio. Every sample grey; blue the samples
    non-dominated over all four ratios; an orange staircase joins the samples non-dominated in
    that plane; the passive suspension (1, 1) a black cross, the base gains a red star. ``ax``:
    two Axes to draw in (the title then goes above the first), or None for a new figure.
    Returns the figure."""
    PROJECTIONS = result.PROJECTIONS

    if ax is None:
        fig = new_figure((PAGE_WIDTH, 3.9))
        axes = fig.subplots(1, 2)
    else:
        axes = given_axes(ax, len(PROJECTIONS), "one per panel")
        fig = axes[0].figure
    for a, (x, y) in zip(axes, PROJECTIONS):
        _draw_plane(a, result, x, y)
    axes[0].legend(loc="best", fontsize="small")
    st = result.settings
    title = (
        f"{suspension_label(result.suspension)}: "
        f"{len(result.ratios)} gain sets ({st.get('n_samples', '?')} Sobol' samples, seed "
        f"{st.get('seed', '?')}, and the base gains), lower is better\n"
        f"{describe_scenario(result.scenario)}, {result.scenario.get('duration_s', 0):g} s, "
        f"{st.get('damper', '?')} dampers"
    )
    if ax is None:
        set_title(fig, title)
    else:
        axes[0].set_title(title, fontsize="small", loc="left")
    # the in-sample note is the caption's (`pareto_caption`), not drawn: a journal sets it there
    return fig


def pareto_caption(result) -> str:
    """The caption of `plot_pareto`'s figure of ``result`` (a
    `railride.studies.pareto.ParetoResult`): what each mark is and, where it applies, the
    in-sample note (``result.note``). Written beside the figure as pareto_caption.txt
    (`railride.output.files.write_pareto_outputs`) and printed by ``railride pareto``."""
    st = result.settings
    (x, y1), (_, y2) = result.PROJECTIONS[:2]
    text = (
        f"{suspension_label(result.suspension)}: the RMS of the carbody responses of "
        f"{len(result.ratios)} gain sets as ratios to the passive suspension's (RMS / RMS(passive), "
        f"lower is better; {st.get('n_samples', '?')} Sobol' samples of the gains, seed "
        f"{st.get('seed', '?')}, and the base gains), {x} ratio against the {y1} ratio (left) and "
        f"against the {y2} ratio (right), log axes. Grey: every sampled gain set; blue: the gain sets "
        "non-dominated over all four ratios; orange staircase through open circles: those "
        "non-dominated in the plane drawn; black cross: passive (1, 1); red star: the base gains "
        f"({st.get('base_gains', '?')}). {describe_scenario(result.scenario)}, "
        f"{result.scenario.get('duration_s', 0):g} s, {st.get('damper', '?')} dampers."
    )
    return text + (f" {result.note}" if result.note else "")
