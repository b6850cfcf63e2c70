"""The figures of railride.plots: what they draw, that each draws into the Axes it is given
and returns their figure, and that none is left registered with pyplot."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import railride as rr
from railride.run import rig
from railride.analysis.spectra import FRF_PATTERNS, comparison_psd, frf_frame
from railride.studies.pareto import ParetoResult
from railride.plots.comparison import (
    plot_comparison_damper_forces,
    plot_comparison_psd,
    plot_comparison_response,
    plot_comparison_voltages,
)
from railride.plots.frf import plot_frf
from railride.plots.pareto import plot_pareto
from railride.plots.ride import plot_body_responses
from railride.plots.rig import plot_hysteresis, plot_tracking
from railride.plots.sweep import plot_sweep, plot_sweep_comfort
from railride.studies.sweep import COMFORT_COLUMNS, SweepResult
from railride.studies.sweep import grid as sweep_grid
from railride.studies.sweep import metric_columns as sweep_metric_columns
from railride.plots.tuning import plot_sensitivity
from railride.run.simulation import simulate
from railride.output.tables import modes_frame
from railride.model.track import scenario
from railride.studies.tuning import Curve
from railride.model.vehicle import Vehicle


@pytest.fixture(scope="module")
def result():
    return simulate(scenario("paper-sine", duration=1.0))


@pytest.fixture(scope="module")
def batch():
    return simulate([scenario("paper-sine", duration=0.5), scenario("bump", duration=0.5)])


@pytest.fixture(scope="module")
def results(result):
    """One result of each type, with the plot functions that draw it: (function, arguments,
    keyword arguments, number of panels)."""
    comparison = rr.compare(scenario("paper-sine", duration=0.5), controllers=["pid"])
    cycles = rig.cycles("railway", 0.01, 1.0, [0.0, 1.0], n_cycles=2)
    tracking = rig.track(n_cycles=2)
    curves = [
        Curve("pid", 1, "pid.kp", np.array([0.0, 1e3, 1e4]), np.array([1.0, 0.8, 0.9]), 1e3),
        Curve("pid", 1, "pid.kd", np.array([1e2, 1e3]), np.array([0.7, 0.75]), 1e2),
    ]
    # a sweep's result without its runs: the grid's cases, and metrics made up for them
    runs = [
        {
            "acceleration_m_s2_rms": 0.3,
            "displacement_m_rms": 0.03,
            "pitch_deg_rms": 0.9,
            "roll_deg_rms": 2.0,
            "centre_N_MV_z": 1.2,
            "centre_aw_Wk": 0.2,
        }
    ]
    runs += [
        {
            "acceleration_m_s2_rms": 0.3 + v / 10,
            "displacement_m_rms": 0.03,
            "pitch_deg_rms": 0.8,
            "roll_deg_rms": 1.9,
            "centre_N_MV_z": 1.0 + v,
            "centre_aw_Wk": 0.2,
        }
        for v in (0.0, 1.0, 2.0)
    ]
    columns = sweep_metric_columns() + list(COMFORT_COLUMNS)
    sweep = SweepResult(
        sweep_grid(["passive", "mr"], voltage=[0.0, 1.0, 2.0], duration=2.0),
        pd.DataFrame([{**dict.fromkeys(columns, 0.0), **r} for r in runs]),
        comfort=True,
    )
    vehicle = Vehicle(rr.VehicleParams.preset("paper"))
    frequency = np.geomspace(0.2, 20.0, 40)
    frf = frf_frame({p: vehicle.frequency_response(frequency, 20.0, p) for p in FRF_PATTERNS})
    modes = modes_frame([m.to_dict() for m in vehicle.modes()])
    pareto = ParetoResult(
        "pid",
        ("pid.kp", "pid.kd"),
        np.array([[0.0, 1.0], [0.0, 1.0]]),
        np.array([[1.0, 1.0], [2.0, 3.0], [4.0, 5.0]]),
        np.array([[0.3, 0.03, 0.8, 1.9], [0.25, 0.03, 0.9, 1.8], [0.35, 0.02, 0.7, 2.1]]),
        np.array([0.32, 0.035, 0.94, 2.0]),
        {"name": "paper-sine", "duration_s": 1.0},
        {"n_samples": 2, "seed": 0, "base_gains": "shipped", "damper": "railway"},
    )
    return [
        (plot_body_responses, (result.dataset,), {}, 4),
        (plot_comparison_response, (comparison, "pitch"), {}, 1),
        (plot_comparison_damper_forces, (comparison,), {}, 2 * 4),  # passive and PID x 4 corners
        (plot_comparison_voltages, (comparison,), {}, 1 * 4),  # PID x 4 corners
        (plot_comparison_psd, (comparison_psd(comparison.combined()),), {}, 1),
        (plot_hysteresis, (cycles,), {}, 2),
        (plot_tracking, (tracking,), {}, 2),
        (plot_sensitivity, (curves,), {}, 2),
        (plot_sweep, (sweep,), {}, 4),
        (plot_sweep_comfort, (sweep,), {}, 2),
        (plot_frf, (frf, modes), {}, 8),  # magnitude and phase of four responses
        (plot_pareto, (pareto,), {}, 2),
    ]


def test_body_responses(result, tmp_path):
    import matplotlib.pyplot as plt

    path = tmp_path / "fig.png"
    fig = plot_body_responses(result.dataset, path)
    axes = fig.get_axes()
    assert len(axes) == 4
    labels = [ax.get_ylabel() for ax in axes]
    assert "m/s" in labels[0] and "(m)" in labels[1] and "deg" in labels[2] and "deg" in labels[3]
    assert axes[-1].get_xlabel() == "time (s)"
    assert "paper-sine" in fig._suptitle.get_text()
    # pitch is plotted in degrees
    y = axes[2].lines[0].get_ydata()
    np.testing.assert_allclose(y, np.rad2deg(result.dataset["carbody_pitch"].values))
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["fig.png"]
    assert plt.get_fignums() == []  # nothing registered with pyplot


def test_body_responses_one_line_per_sample(batch):
    fig = plot_body_responses(batch.dataset)
    assert fig.get_axes()
    for ax in fig.get_axes():
        assert len(ax.lines) == 2


def test_each_plot_draws_into_the_given_axes_and_returns_their_figure(results):
    import matplotlib.pyplot as plt

    for plot, args, kwargs, panels in results:
        mine = Figure()
        axes = mine.subplots(1, panels, squeeze=False).ravel()
        given = axes[0] if panels == 1 else axes
        assert plot(*args, ax=given, **kwargs) is mine, plot.__name__
        assert mine.get_axes() == list(axes), plot.__name__  # no Axes of its own added
        for ax in axes:
            assert ax.has_data() or ax.texts, (plot.__name__, ax)
        own = plot(*args, **kwargs)  # ax None: a figure of its own
        assert isinstance(own, Figure) and own is not mine and own.get_axes(), plot.__name__
    assert plt.get_fignums() == []  # no figure left registered with pyplot


def test_a_wrong_number_of_axes_is_refused(results):
    for plot, args, kwargs, panels in results:
        if panels == 1:
            continue
        axes = Figure().subplots(1, panels + 1)
        with pytest.raises(ValueError, match=f"ax: {panels} Axes"):
            plot(*args, ax=axes, **kwargs)


def test_plots_take_their_documented_type(result):
    with pytest.raises(ValueError, match="comparison: expected a railride.studies.comparison.Comparison"):
        plot_comparison_response(result.dataset, "pitch")
    with pytest.raises(ValueError, match="cycles: expected a railride.run.rig.Cycles"):
        plot_hysteresis(result.dataset)


# -- figure files: formats and resolution ---------------------------------------------------------
def _png_size(path) -> tuple[int, int]:
    """Width and height of a PNG file from its IHDR chunk."""
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and data[12:16] == b"IHDR"
    return int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")


def test_save_writes_every_figure_format_readable(result, tmp_path):
    import xml.etree.ElementTree as ET

    out = tmp_path / "out"
    paths = result.save(out, figure_formats=("png", "pdf", "svg"), dpi=50)
    names = {p.name for p in paths}
    assert {"body_responses.png", "body_responses.pdf", "body_responses.svg", "ride.nc"} <= names
    assert (out / "body_responses.pdf").read_bytes().startswith(b"%PDF")
    assert ET.parse(out / "body_responses.svg").getroot().tag == "{http://www.w3.org/2000/svg}svg"
    assert _png_size(out / "body_responses.png")[0] > 0
    only = result.save(tmp_path / "pdf", figure_formats="pdf")
    assert [p.name for p in only if p.name.startswith("body")] == ["body_responses.pdf"]


def test_png_size_follows_dpi(result, tmp_path):
    low = _png_size(result.save(tmp_path / "a", dpi=40)[-1])
    high = _png_size(result.save(tmp_path / "b", dpi=120)[-1])
    assert high == (3 * low[0], 3 * low[1])
    width_in, height_in = result.plot().get_size_inches()
    assert low == (round(40 * width_in), round(40 * height_in))


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"figure_formats": ("tiff",)}, "figure_formats = ('tiff',): 'tiff' is not a figure format"),
        ({"figure_formats": ()}, "figure_formats = (): no format given"),
        ({"dpi": 0}, "dpi = 0: must be a finite number >= 10 and <= 1200"),
        ({"dpi": 1201}, "dpi = 1201: must be"),
        ({"dpi": float("nan")}, "dpi = nan: must be"),
        ({"dpi": "300"}, "dpi = '300': must be"),
    ],
)
def test_bad_figure_options_are_refused_before_anything_is_written(result, tmp_path, kwargs, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        result.save(tmp_path / "out", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_the_same_figure_gives_the_same_file(result, tmp_path):
    for k in (1, 2):
        result.save(tmp_path / str(k), figure_formats="pdf,svg,png")
    for name in ("body_responses.pdf", "body_responses.svg", "body_responses.png"):
        assert (tmp_path / "1" / name).read_bytes() == (tmp_path / "2" / name).read_bytes(), name
    pdf = (tmp_path / "1" / "body_responses.pdf").read_bytes()
    assert b"/Subtype /Type3" not in pdf and b"/Subtype /CIDFontType2" in pdf  # TrueType outlines


def test_figure_options_read_a_comma_list():
    from railride.plots import FigureOptions

    options = FigureOptions("SVG, png,svg", 300)
    assert options.figure_formats == ("svg", "png") and options.dpi == 300.0
    assert options.names("pitch") == ["pitch.svg", "pitch.png"]


# -- the house style ------------------------------------------------------------------------------
def test_own_figures_take_the_style_and_leave_the_global_settings_alone(result, tmp_path):
    import matplotlib

    from railride.plots import STYLE, save_figure

    before = dict(matplotlib.rcParams)
    fig = plot_body_responses(result.dataset)
    save_figure(fig, tmp_path / "f.png")  # drawn outside the style's context
    assert dict(matplotlib.rcParams) == before
    ticks = fig.get_axes()[0].yaxis.get_major_ticks()
    assert len(ticks) > 2 and all(t.label1.get_fontsize() == STYLE["ytick.labelsize"] for t in ticks)
    # into the caller's Axes: the caller's style
    mine = Figure()
    plot_body_responses(result.dataset, ax=mine.subplots(4, 1))
    mine.canvas.draw()
    label = mine.get_axes()[0].yaxis.get_major_ticks()[0].label1
    theirs = matplotlib.font_manager.FontProperties(size=matplotlib.rcParams["ytick.labelsize"])
    assert label.get_fontsize() == theirs.get_size_in_points() != STYLE["ytick.labelsize"]


def test_titles_fit_the_figure_width(results):
    from railride.plots.frf import plot_frf

    long = "a title far longer than any figure is wide: " + "carbody pitch and roll " * 12
    figures = [plot(*args, **kwargs) for plot, args, kwargs, _ in results]
    frame, modes = results[-2][1]
    figures.append(plot_frf(frame, modes, title=long))
    for fig in figures:
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        width = fig.get_figwidth() * fig.dpi
        title = fig._suptitle
        if title is not None and title.get_text():
            box = title.get_window_extent(renderer)
            assert box.x0 >= -1 and box.x1 <= width + 1, (title.get_text(), box, width)
        for ax in fig.get_axes():
            for text in (ax.title, ax._left_title, ax._right_title):
                if text.get_text():
                    box = text.get_window_extent(renderer)
                    assert box.x0 >= -1 and box.x1 <= width + 1, (text.get_text(), box, width)


def test_sensitivity_panel_titles_do_not_run_into_each_other():
    # the longest gain names with their units, side by side as `railride tune` draws them
    names = ["ride_attitude.kd_theta", "clipped_optimal.qd_theta", "ride_attitude.kp_theta", "skyhook_on_off.c_phi"]
    values, scores = np.array([0.0, 1e5, 1e6]), np.array([1.0, 0.8, 0.9])
    curves = [Curve("sas-attitude-ride", 1, n, values, scores, 1e5) for n in names]
    fig = plot_sensitivity(curves)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    boxes = [ax.title.get_window_extent(renderer) for ax in fig.get_axes() if ax.title.get_text()]
    assert len(boxes) == 4
    for left, right in zip(boxes, boxes[1:]):
        if abs(left.y0 - right.y0) < 1:  # on the same row
            assert left.x1 <= right.x0, (left, right)


# -- the metric window: the start-up transient ----------------------------------------------------
def _with_transient(ds, height: float = 100.0, until: float = 0.2):
    """``ds`` with a start-up spike of ``height`` in the acceleration before ``until`` s."""
    out = ds.copy(deep=True)
    early = out["time"] < until
    out["carbody_acceleration"] = out["carbody_acceleration"].where(~early, height)
    return out


def test_time_history_y_limits_come_from_the_metric_window(result):
    ds = _with_transient(result.dataset)
    inside = ds["carbody_acceleration"].sel(time=slice(0.3, 1.0)).values
    autoscaled = plot_body_responses(ds).get_axes()[0]
    assert autoscaled.get_ylim()[1] >= 100.0  # without a window the spike sets the scale
    fig = plot_body_responses(ds, window=(0.3, 1.0))
    a = fig.get_axes()[0]
    low, high = a.get_ylim()
    assert high < 10.0 * np.abs(inside).max() < 100.0
    assert low <= inside.min() and high >= inside.max()
    assert a.lines[0].get_ydata().max() == 100.0  # the transient is still drawn, clipped
    assert a.lines[0].get_xdata()[0] == ds["time"].values[0]  # the whole run
    shaded = [p for p in a.patches if p.get_x() == pytest.approx(0.0)]
    assert shaded and shaded[0].get_width() == pytest.approx(0.3)
    assert "metric window 0.3-1 s" in fig._suptitle.get_text()


def test_the_whole_run_as_window_keeps_autoscale(result):
    ds = _with_transient(result.dataset)
    a = plot_body_responses(ds, window=(0.0, float(ds["time"][-1]))).get_axes()[0]
    assert a.get_ylim()[1] >= 100.0 and not a.patches


def test_comparison_and_tracking_use_their_metric_window():
    # the sine enters through its taper: the window's end leaves the larger responses out
    comparison = rr.compare(scenario("paper-sine", duration=1.0), controllers=["pid"], window=(0.1, 0.6), bounds=False)
    ds = comparison.combined()
    a = plot_comparison_response(comparison, "acceleration").get_axes()[0]
    inside = ds["carbody_acceleration"].sel(time=slice(0.1, 0.6)).values
    whole = ds["carbody_acceleration"].values
    low, high = a.get_ylim()
    assert low <= inside.min() and high >= inside.max()
    assert high - low < 1.2 * (inside.max() - inside.min())
    assert (whole.max() - whole.min()) > 1.2 * (inside.max() - inside.min())  # the window matters here
    forces = plot_comparison_damper_forces(comparison).get_axes()
    assert forces and all(len(f.patches) == 2 for f in forces)  # every panel shaded before 0.1 s and after 0.6 s
    tracking = rig.track(n_cycles=3)
    f_axes = plot_tracking(tracking).get_axes()[0]
    start, end = tracking.window
    kept = tracking.dataset.sel(time=slice(start, end))
    kn = np.concatenate([kept["F"].values, kept["desired_force"].values]) / 1e3
    low, high = f_axes.get_ylim()
    assert low <= kn.min() and high >= kn.max() and high - low < 1.2 * (kn.max() - kn.min())
    assert f_axes.patches[0].get_width() == pytest.approx(start - float(tracking.dataset["time"][0]))  # start-up


# -- legends say what differs ---------------------------------------------------------------------
def _legend_texts(fig) -> list[str]:
    return [t.get_text() for ax in fig.get_axes() if ax.get_legend() for t in ax.get_legend().get_texts()]


def test_batch_legends_name_what_differs_between_the_samples():
    speeds = simulate([scenario("paper-sine", duration=0.3, speed=v) for v in (40.0, 55.56)])
    assert _legend_texts(plot_body_responses(speeds.dataset)) == ["V = 40 m/s", "V = 55.56 m/s"]
    seeds = simulate([scenario("fra4", duration=0.3, seed=s) for s in (1, 3)])
    assert _legend_texts(plot_body_responses(seeds.dataset)) == ["seed 1", "seed 3"]
    paper = rr.VehicleParams.preset("paper")
    loads = simulate(scenario("paper-sine", duration=0.3), [paper, paper.loaded(1.2)])
    assert _legend_texts(plot_body_responses(loads.dataset)) == ["load x1", "load x1.2"]
    damping = simulate(scenario("paper-sine", duration=0.3), [paper, paper.replace(c_sz=6e4)])
    assert _legend_texts(plot_body_responses(damping.dataset))[1] == "c_sz = 6e+04 N s/m"
    volts = simulate(
        scenario("paper-sine", duration=0.3),
        suspension=[rr.Suspension.semi_active("railway", voltage=v) for v in (0.0, 2.25)],
    )
    assert _legend_texts(plot_body_responses(volts.dataset)) == ["0 V", "2.25 V"]
    alike = simulate([scenario("paper-sine", duration=0.3)] * 2)
    assert _legend_texts(plot_body_responses(alike.dataset)) == ["sample 0", "sample 1"]


def test_study_conditions_name_the_speed_and_the_load_factor():
    from railride.plots.study import _condition_label

    assert _condition_label(40.0, 1.2, 1.0, "none", 1) == "40 m/s\nload x1.2"
    assert _condition_label(40.0, 1.2, 1.0, "none", 1, crowded=True) == "40 m/s, load x1.2"
    assert _condition_label(55.56, 1.0, 0.9, "1R-off", 4) == "55.56 m/s\nload x1\nk_sz x 0.9\n1R-off\ndelay 4"


# -- frequency responses: magnitude and phase -----------------------------------------------------
def test_frf_has_a_phase_panel_per_response(results):
    frame, modes = next(args for plot, args, _, _ in results if plot is plot_frf)
    fig = plot_frf(frame, modes)
    axes = fig.get_axes()
    assert len(axes) == 8
    phase = [a for a in axes if a.get_ylabel() == "phase (deg)"]
    assert len(phase) == 4
    for a in phase:
        assert a.get_ylim() == (-195.0, 195.0)
        assert a.lines
        for line in a.lines:
            y = np.asarray(line.get_ydata(), dtype=float)
            y = y[np.isfinite(y)]
            assert y.size and (np.abs(y) <= 180.0).all()
    # bounce on slow in-phase rails: the car follows the mean of its four wheelsets, which meet
    # the rail at 0, 2b, 2l and 2l + 2b behind the leading one (the fixture's speed: 20 m/s), so
    # it lags by 360 f (l + b) / V; its acceleration, -omega^2 times the bounce, half a turn more
    paper = rr.VehicleParams.preset("paper")
    lowest = float(frame["frequency_hz"].min())
    lag = -360.0 * lowest * (paper.l + paper.b) / 20.0
    bounce, acceleration = phase[0], phase[3]
    first = [ln for ln in bounce.lines if np.asarray(ln.get_xdata())[0] == lowest][0]
    assert first.get_ydata()[0] == pytest.approx(lag, abs=3.0)
    first = [ln for ln in acceleration.lines if np.asarray(ln.get_xdata())[0] == lowest][0]
    assert first.get_ydata()[0] == pytest.approx(lag + 180.0, abs=3.0)
