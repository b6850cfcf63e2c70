"""The figures of railride.plots: what they draw, that each draws into the Axes it is given
and returns their figure, and that none is left registered with pyplot."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

import railride as rr
from railride import rig
from railride.analysis import FRF_PATTERNS, comparison_psd, frf_frame
from railride.pareto import ParetoResult
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
from railride.sweep import COMFORT_COLUMNS, SweepResult
from railride.sweep import grid as sweep_grid
from railride.sweep import metric_columns as sweep_metric_columns
from railride.plots.tuning import plot_sensitivity
from railride.simulation import simulate
from railride.tables import modes_frame
from railride.track import scenario
from railride.tuning import Curve
from railride.vehicle import Vehicle


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
        (plot_frf, (frf, modes), {}, 4),
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
    with pytest.raises(ValueError, match="comparison: expected a railride.comparison.Comparison"):
        plot_comparison_response(result.dataset, "pitch")
    with pytest.raises(ValueError, match="cycles: expected a railride.rig.Cycles"):
        plot_hysteresis(result.dataset)
