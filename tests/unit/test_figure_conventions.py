"""What a reviewer asks of the figures: categories drawn as categories (seeds as markers, never
joined), a sweep over two axes drawn (one line per value of the second), a sweep it cannot
draw saying why, the Pareto view's caveat in its caption rather than in the drawing, the
sensitivity figure on pages whose ticks do not collide, and one way of writing a unit."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from railride.studies.sweep import COMFORT_COLUMNS, SweepResult, metric_columns
from railride.studies.sweep import grid as sweep_grid
from railride.studies.tuning import PARAMETERS
from railride.studies.tune_result import Curve

PLOTS = Path(__file__).resolve().parents[2] / "railride" / "plots"


def _fake_sweep(g) -> SweepResult:
    """A sweep's result without its runs: the grid's cases, each with its own made-up metrics
    (run i has 0.1 + 0.01 i in every column)."""
    rows = [dict.fromkeys(metric_columns() + list(COMFORT_COLUMNS), 0.1 + 0.01 * i) for i in range(len(g.cases))]
    return SweepResult(g, pd.DataFrame(rows), comfort=True)


def _data_lines(ax):
    """The Axes' lines that carry data (not the horizontal "not swept" or class-bound lines)."""
    return [line for line in ax.get_lines() if len(set(np.asarray(line.get_xdata(), dtype=float))) > 1]


# -- 1. categories are not joined ------------------------------------------------------------------
def test_a_track_seed_sweep_draws_markers_at_labelled_categories_not_a_line():
    from railride.plots.sweep import plot_sweep

    result = _fake_sweep(sweep_grid(["passive", "pid"], scenario="fra4", track_seed=[3, 7, 11], duration=1.0))
    fig = plot_sweep(result)
    for ax in fig.get_axes():
        lines = _data_lines(ax)
        assert len(lines) == 2  # passive and PID
        for line in lines:
            assert line.get_linestyle() == "None" and line.get_marker() not in ("None", "", None)
            # evenly spaced positions, 0, 1, 2 (each series nudged aside), not at the seeds' values
            assert np.allclose(np.round(line.get_xdata()), [0, 1, 2])
    bottom = fig.get_axes()[2]
    assert [t.get_text() for t in bottom.get_xticklabels()] == ["3", "7", "11"]
    assert bottom.get_xlabel() == "track seed"


def test_an_ordered_axis_is_still_drawn_as_lines():
    from railride.plots.sweep import plot_sweep

    fig = plot_sweep(_fake_sweep(sweep_grid(["passive"], speed=[20.0, 40.0, 60.0], duration=1.0)))
    (line,) = _data_lines(fig.get_axes()[0])
    assert line.get_linestyle() not in ("None", "", " ")
    assert list(line.get_xdata()) == [20.0, 40.0, 60.0]


# -- 2. two axes: a figure; more: a note ------------------------------------------------------------
def test_a_sweep_over_two_axes_draws_one_line_per_value_of_the_second(tmp_path):
    from railride.plots.sweep import plot_sweep, sweep_plot_axes

    g = sweep_grid(["passive", "mr"], speed=[20.0, 40.0, 60.0], voltage=[0.0, 1.0], duration=1.0)
    result = _fake_sweep(g)
    assert sweep_plot_axes(result) == ("speed_m_s", "voltage_v")
    assert result.figure_note is None
    ax = plot_sweep(result).get_axes()[0]
    lines = _data_lines(ax)
    labels = [line.get_label() for line in lines]
    mr = "MR (constant voltage), command voltage"
    assert labels == ["Passive", f"{mr} 0 V", f"{mr} 1 V"]
    # each line holds its own runs: the rows of that voltage, against speed
    frame = result.to_pandas()
    for line, volts in zip(lines[1:], (0.0, 1.0)):
        rows = frame[(frame["suspension"] == "mr") & (frame["voltage_v"] == volts)].sort_values("speed_m_s")
        assert list(line.get_xdata()) == list(rows["speed_m_s"])
        assert list(line.get_ydata()) == pytest.approx(list(rows["acceleration_m_s2_rms"]))
    assert len({line.get_color() for line in lines[1:]}) == 2
    names = [p.name for p in result.save(tmp_path / "two")]
    assert names == ["sweep.json", "sweep.png", "comfort.png"]


def test_a_categorical_second_axis_goes_to_the_lines_and_the_ordered_one_along_x():
    from railride.plots.sweep import sweep_plot_axes

    g = sweep_grid(["passive"], scenario="fra4", track_seed=[0, 1, 2, 3], speed=[30.0, 50.0], duration=1.0)
    assert sweep_plot_axes(_fake_sweep(g)) == ("speed_m_s", "track_seed")


def test_a_sweep_over_three_axes_says_why_it_has_no_figure(tmp_path):
    g = sweep_grid(["mr"], speed=[20.0, 40.0], wavelength=[30.0, 60.0], voltage=[0.0, 1.0], duration=1.0)
    result = _fake_sweep(g)
    note = result.figure_note
    assert "\n" not in note and "3 axes" in note
    assert all(axis in note for axis in ("speed_m_s", "wavelength_m", "voltage_v"))
    assert [p.name for p in result.save(tmp_path / "three")] == ["sweep.json"]
    with pytest.raises(ValueError, match="3 axes"):
        result.plot()


# -- 3. the Pareto view's caveat goes in the caption --------------------------------------------------
def _pareto(note):
    from railride.studies.pareto import ParetoResult

    return ParetoResult(
        "pid",
        ("pid.kp", "pid.kd"),
        np.array([[0.0, 1.0], [0.0, 1.0]]),
        np.array([[1.0, 1.0], [2.0, 3.0], [4.0, 5.0]]),
        np.array([[0.3, 0.03, 0.8, 1.9], [0.25, 0.03, 0.9, 1.8], [0.35, 0.02, 0.7, 2.1]]),
        np.array([0.32, 0.035, 0.94, 2.0]),
        {"name": "paper-sine", "duration_s": 1.0},
        {"n_samples": 2, "seed": 0, "base_gains": "shipped", "damper": "railway"},
        note=note,
    )


def _texts(fig) -> list[str]:
    from matplotlib.text import Text

    return [t.get_text() for t in fig.findobj(Text) if t.get_text()]


def test_the_pareto_caveat_is_in_the_caption_file_not_in_the_figure(tmp_path):
    import matplotlib.pyplot as plt

    from railride.plots.pareto import plot_pareto

    note = "The base gains (shipped) were tuned on this same single track and are judged on it."
    result = _pareto(note)
    fig = plot_pareto(result)
    assert not any("tuned on this same" in text for text in _texts(fig))
    _, axes = plt.subplots(1, 2)
    assert not any("tuned on this same" in text for text in _texts(plot_pareto(result, axes)))
    plt.close("all")
    folder = tmp_path / "p"
    result.save(folder)
    caption = (folder / "pareto_caption.txt").read_text()
    assert note in caption and "black cross: passive (1, 1)" in caption


# -- 4. the sensitivity figure: pages, ticks apart ------------------------------------------------------
def _every_law_curves() -> list[Curve]:
    """Two passes over every gain `railride tune` tunes (every law and the inner loop), each gain
    around its own made-up value, decades apart from gain to gain, the value 0 in the first pass."""
    rng = np.random.default_rng(1)
    curves = []
    for law, parameters in PARAMETERS.items():
        for p in parameters:
            base = 10 ** rng.uniform(-2.0, 6.0)
            first = np.concatenate([[0.0], base * np.geomspace(1 / 30, 30, 13)])
            curves.append(Curve(law, 1, p, first, 1 + rng.random(first.size), base))
            second = base * np.geomspace(1 / 1.5, 1.5, 7)  # a narrow pass: within one decade
            curves.append(Curve(law, 2, p, second, 1 + rng.random(second.size), base))
    return curves


def _overlaps(boxes) -> list:
    return [(a, b) for i, a in enumerate(boxes) for b in boxes[i + 1 :] if a.overlaps(b)]


def test_the_sensitivity_figure_of_every_law_comes_in_pages_whose_ticks_do_not_collide(tmp_path):
    from railride.output.files import write_tune_outputs
    from railride.plots.tuning import PAGE_PANELS, plot_sensitivity_pages

    curves = _every_law_curves()
    n_parameters = len({c.parameter for c in curves})
    assert n_parameters > 2 * PAGE_PANELS  # the case of the report: 43 panels on one page
    pages = plot_sensitivity_pages(curves)
    drawn = []
    for fig in pages:
        panels = [ax for ax in fig.get_axes() if ax.get_visible()]
        assert 1 <= len(panels) <= PAGE_PANELS
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        for ax in panels:
            drawn.append(ax.get_title())
            for labels in (ax.get_xticklabels(), ax.get_yticklabels()):
                boxes = [t.get_window_extent(renderer) for t in labels if t.get_visible() and t.get_text()]
                assert len(boxes) >= 2, (ax.get_title(), [t.get_text() for t in labels])
                assert not _overlaps(boxes), (ax.get_title(), [t.get_text() for t in labels])
    assert len(drawn) == n_parameters  # every gain on some page, once
    paths = write_tune_outputs(curves, tmp_path / "t", {"schema": "test"}, "# gains\n")
    names = [p.name for p in paths]
    assert names == ["gains.toml"] + [
        "sensitivity.png" if k == 0 else f"sensitivity_{k + 1}.png" for k in range(len(pages))
    ] + ["curves.csv", "tune.json"]


def test_a_few_gains_stay_on_one_page_named_as_before(tmp_path):
    from railride.output.files import TUNE_FILES, write_tune_outputs

    curves = [c for c in _every_law_curves() if c.controller == "pid"]
    paths = write_tune_outputs(curves, tmp_path / "t", {"schema": "test"}, "# gains\n")
    assert [p.name for p in paths] == list(TUNE_FILES)


# -- 5. units in parentheses ---------------------------------------------------------------------------
#: a unit in square brackets: "[Hz]", "[(m/s²)²/Hz]", "[m/s$^2$]", "[kN]", "[-]"
BRACKETED_UNIT = re.compile(r"\[\(?[-A-Za-z%°µ/$^{}²³()· ]*(?:Hz|m|s|N|V|deg|rad|kg|%|-)[-$^{}²³)·/ ]*\]")


def _strings(path: Path) -> list[tuple[int, str]]:
    """(line, text) of every string in the module ``path`` that is not a docstring, the parts of
    f-strings included: the texts a figure can show."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {
        id(node.body[0].value)
        for node in ast.walk(tree)
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.ClassDef, ast.AsyncFunctionDef))
        and node.body
        and isinstance(node.body[0], ast.Expr)
        and isinstance(node.body[0].value, ast.Constant)
    }
    return [
        (node.lineno, node.value)
        for node in ast.walk(tree)
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings
    ]


def test_the_pattern_finds_a_bracketed_unit_and_passes_a_parenthesised_one():
    assert BRACKETED_UNIT.search("frequency [Hz]") and BRACKETED_UNIT.search("PSD [(m/s²)²/Hz]")
    assert BRACKETED_UNIT.search("force [kN]") and BRACKETED_UNIT.search("scale [-]")
    assert not BRACKETED_UNIT.search("frequency (Hz)") and not BRACKETED_UNIT.search("PSD ((m/s$^2$)$^2$/Hz)")
    assert not BRACKETED_UNIT.search("axes[0]") and not BRACKETED_UNIT.search("$10^{3}$")


@pytest.mark.parametrize("module", [p.name for p in sorted(PLOTS.glob("*.py"))])
def test_figures_give_units_in_parentheses_never_in_brackets(module):
    found = [(line, text) for line, text in _strings(PLOTS / module) if BRACKETED_UNIT.search(text)]
    assert not found, f"{module}: units in brackets; write them as 'quantity (unit)': {found}"


def test_the_labels_of_the_figures_built_here_give_their_units_in_parentheses():
    from railride.plots.pareto import plot_pareto
    from railride.plots.sweep import plot_sweep, plot_sweep_comfort
    from railride.plots.tuning import plot_sensitivity

    sweep = _fake_sweep(sweep_grid(["passive", "mr"], speed=[20.0, 40.0], voltage=[0.0, 1.0], duration=1.0))
    figures = [plot_sweep(sweep), plot_sweep_comfort(sweep), plot_pareto(_pareto(None))]
    figures.append(plot_sensitivity([c for c in _every_law_curves() if c.controller == "pid"]))
    labels = [text for fig in figures for ax in fig.get_axes() for text in (ax.get_xlabel(), ax.get_ylabel())]
    assert "speed (m/s)" in labels and "acceleration RMS (m/s$^2$)" in labels
    assert not [text for text in labels if BRACKETED_UNIT.search(text)]


def test_a_page_lists_only_the_passes_it_draws():
    from railride.plots.tuning import plot_sensitivity_pages

    curves = _every_law_curves()
    # a third pass of the first gain only: on the first page, not on the others
    first = curves[1]
    curves.append(Curve(first.controller, 3, first.parameter, first.values, first.objective, first.chosen))
    pages = plot_sensitivity_pages(curves)
    labels = [[t.get_text() for leg in fig.legends for t in leg.get_texts()] for fig in pages]
    assert "pass 3" in labels[0]
    assert len(pages) > 1 and all("pass 3" not in page and "pass 1" in page for page in labels[1:])


def test_the_tuning_figure_title_breaks_lines_at_spaces_only():
    import dataclasses

    import railride as rr

    result = rr.tune(("pid",), scenario_options={"duration": 0.3}, n_values=3, budget=5, before_after=False)
    # every law's name in the title, as `railride tune` lists them: a wrap at 100 characters
    # split "clipped-optimal" at its hyphen
    every = ["inner", "pid", "sas-attitude", "sas-attitude-ride", "skyhook", "skyhook-on-off", "groundhook"]
    result = dataclasses.replace(result, controllers=every + ["hybrid", "clipped-optimal"])
    for fig in result.plot_pages():
        title = fig._suptitle.get_text()
        assert "clipped-optimal" in title.replace("\n", " ")
        assert not any(line.endswith("-") for line in title.splitlines()), title
