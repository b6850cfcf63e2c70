"""The report layer of the Pareto view (`railride.pareto`): its figure and its result folder.

Built like `railride.report`: matplotlib's object API on the Agg canvas (no pyplot, no window),
files written all or nothing by `railride.report.write_folder`.
"""

from __future__ import annotations

from .report import _json_text, _new_figure, describe_scenario, write_folder

#: axis label of each ratio
RATIO_LABELS = {
    "acceleration": "heave acceleration at the carbody CG:\nRMS / RMS(passive)",
    "displacement": "heave displacement at the carbody CG:\nRMS / RMS(passive)",
    "pitch": "carbody pitch angle: RMS / RMS(passive)",
    "roll": "carbody roll angle: RMS / RMS(passive)",
}
SUSPENSION_LABELS = {"pid": "PID", "sas-attitude": "SAS (attitude)",
                     "sas-attitude-ride": "SAS (attitude+ride)"}


def plot_pareto(result, ax=None):
    """Two panels of `ParetoResult` ``result``: the acceleration ratio (x) against the pitch
    ratio, and against the roll ratio. Every sample grey; blue the samples non-dominated over
    all four ratios; an orange staircase joins the samples non-dominated in that plane; the
    passive suspension (1, 1) a black cross, the base gains a red star. ``ax``: two Axes to draw
    in, or None for a new figure. Returns the figure."""
    import numpy as np
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    from .pareto import PROJECTIONS, RATIOS

    if ax is None:
        fig = _new_figure((11.0, 5.0))
        axes = fig.subplots(1, 2)
    else:
        axes = list(np.ravel(ax))
        if len(axes) != len(PROJECTIONS):
            raise ValueError(f"ax: {len(PROJECTIONS)} Axes (one per panel), got {len(axes)}")
        fig = axes[0].figure
    ratios = result.ratios
    front = result.non_dominated
    for a, (x, y) in zip(axes, PROJECTIONS):
        rx, ry = ratios[:, RATIOS.index(x)], ratios[:, RATIOS.index(y)]
        plane = result.non_dominated_in(x, y)
        a.scatter(rx, ry, s=10, color="0.65", linewidths=0, label="sample", zorder=2)
        a.scatter(rx[front], ry[front], s=16, color="tab:blue", linewidths=0, zorder=3,
                  label="non-dominated over all four ratios")
        order = np.argsort(rx[plane])
        a.step(rx[plane][order], ry[plane][order], where="post", color="tab:orange",
               linewidth=1.2, zorder=4)
        a.scatter(rx[plane], ry[plane], s=28, facecolors="none", edgecolors="tab:orange",
                  zorder=4, label="non-dominated in this plane")
        a.plot([1.0], [1.0], "x", color="k", markersize=9, markeredgewidth=2, zorder=5,
               label="passive (1, 1)")
        a.plot([rx[0]], [ry[0]], "*", color="tab:red", markersize=14, markeredgecolor="k",
               markeredgewidth=0.5, zorder=6, label=f"base gains ({result.settings.get('base_gains', '?')})")
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
        a.tick_params(labelsize="small")
        a.grid(True, which="major", linewidth=0.4, alpha=0.6)
    axes[0].legend(loc="best", fontsize="x-small")
    st = result.settings
    title = (f"{SUSPENSION_LABELS.get(result.suspension, result.suspension)}: "
             f"{len(ratios)} gain sets ({st.get('n_samples', '?')} Sobol' samples, seed "
             f"{st.get('seed', '?')}, and the base gains), lower is better\n"
             f"{describe_scenario(result.scenario)}, {result.scenario.get('duration_s', 0):g} s, "
             f"{st.get('damper', '?')} dampers")
    if ax is None:
        fig.suptitle(title, fontsize="medium")
        if result.note:
            fig.text(0.5, 0.005, result.note, ha="center", va="bottom", fontsize="small",
                     color="tab:red")
            fig.get_layout_engine().set(rect=(0, 0.04, 1, 0.96))
    else:
        axes[0].set_title(title, fontsize="small", loc="left")
        if result.note:
            axes[-1].set_title(result.note, fontsize="x-small", color="tab:red", wrap=True)
    return fig


def write_pareto(result, folder) -> list:
    """pareto.png (`plot_pareto`), pareto.csv (`to_pandas`) and pareto.json (`to_dict`) into
    ``folder``, all or nothing (`write_folder`). Returns the paths."""
    from .pareto import FILES

    text = _json_text(result.to_dict())  # refuse NaN before any file is written
    frame = result.to_pandas()
    writers = {
        "pareto.png": lambda path: plot_pareto(result).savefig(path, format="png", dpi=120),
        "pareto.csv": lambda path: frame.to_csv(path, index=False),
        "pareto.json": lambda path: path.write_text(text, encoding="utf-8"),
    }
    return write_folder(folder, [(name, writers[name]) for name in FILES])
