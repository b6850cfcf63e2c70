"""The global methods of `railride.studies.optimise`: the convergence of the differential evolution and
the Sobol indices of the objective."""

from __future__ import annotations

import numpy as np

from railride.errors import InputError
from railride.plots._style import PAGE_WIDTH, given_axes, new_figure, set_title, styled


def _expect(value, name: str, kind: str, needs: str):
    """``value`` has the attribute ``needs`` of a ``kind`` (plots import no result module)."""
    if not hasattr(value, needs):
        raise InputError(f"{name}: expected a railride.studies.optimise.{kind}, got {type(value).__name__}")


def _objective_label(definition) -> str:
    kind = getattr(definition, "kind", None)
    return f"objective J ({kind})" if kind else "objective J"


@styled
def plot_convergence(result, ax=None, *, title: str | None = None):
    """The search of `railride.studies.optimise.optimise` (an `OptimiseResult`): per generation
    (0 the initial population) the lowest objective among its runs (dots) and the lowest so far
    (a step line), against the generation. ``ax``: one Axes to draw in (no title then), or None
    for a new figure titled ``title`` (default: the suspension, the generations, the runs and
    the objective reached). Returns the `Figure`."""
    from matplotlib.ticker import MaxNLocator

    _expect(result, "result", "OptimiseResult", "generations")
    frame = result.to_pandas()
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 3.6))
        a = fig.subplots()
    else:
        (a,) = given_axes(ax, 1, "the objective against generation")
        fig = a.figure
    a.plot(frame["generation"], frame["objective"], "o", color="0.55", label="lowest in the generation")
    a.step(frame["generation"], frame["best"], where="post", color="tab:red", linewidth=1.3, label="lowest so far")
    a.xaxis.set_major_locator(MaxNLocator(integer=True))
    a.set_xlabel("generation (0: the initial population)")
    a.set_ylabel(_objective_label(result.objective_definition))
    a.legend()
    if ax is None:
        set_title(
            fig,
            title
            or (
                f"Differential evolution: {result.suspension or 'controller'}, "
                f"{len(result.parameters)} gains, {result.generations} generations, "
                f"{result.n_runs} runs; J = {result.objective:.4g}"
            ),
        )
    return fig


@styled
def plot_indices(result, ax=None, *, title: str | None = None):
    """The Sobol indices of `railride.studies.optimise.sensitivity` (a `SensitivityResult`): per gain,
    a bar of its first-order index (its effect alone) and one of its total index (with every
    interaction), horizontal, the gains top to bottom in their order. ``ax``: one Axes to draw
    in (no title then), or None for a new figure titled ``title`` (default: the suspension and
    the runs). Returns the `Figure`."""
    _expect(result, "result", "SensitivityResult", "first_order")
    names = list(result.parameters)
    y = np.arange(len(names))
    if ax is None:
        fig = new_figure((PAGE_WIDTH, 1.2 + 0.35 * len(names)))
        a = fig.subplots()
    else:
        (a,) = given_axes(ax, 1, "the indices of every gain")
        fig = a.figure
    height = 0.38
    a.barh(y - height / 2, np.asarray(result.first_order, dtype=float), height, color="tab:blue", label="first order")
    a.barh(y + height / 2, np.asarray(result.total, dtype=float), height, color="tab:orange", label="total")
    a.set_yticks(y, names)
    a.invert_yaxis()  # the first gain on top
    a.axvline(0.0, color="0.4", linewidth=0.6)
    a.set_xlabel(f"Sobol index of the {_objective_label(result.objective_definition)}")
    a.grid(False, axis="y")
    a.legend()
    if ax is None:
        set_title(
            fig,
            title
            or (
                f"Sobol indices: {result.suspension or 'controller'}, gains uniform "
                f"in log10 over the search box, {result.n_runs} runs"
            ),
        )
    return fig
