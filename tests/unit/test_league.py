"""The league table: its cases, its means, in-sample flags and refusals."""

import math

import numpy as np
import pytest

from railride.studies.league import league


@pytest.fixture(scope="module")
def table():
    return league(["paper-sine", "fra4"], [30.0, 55.56], track_seeds=[0, 1], controllers=["pid"], duration=2.0)


def test_every_case_once_and_seeds_only_on_random_track(table):
    cases = table.cases[table.cases.controller == "pid"]
    # paper-sine: 2 speeds; fra4: 2 speeds x 2 seeds
    assert len(cases) == 2 + 4
    assert cases[cases.scenario == "paper-sine"].track_seed.isna().all()
    assert sorted(cases[cases.scenario == "fra4"].track_seed) == [0, 0, 1, 1]


def test_summary_is_the_mean_over_the_cases(table):
    summary = table.summary
    pid = table.cases[table.cases.controller == "pid"]
    for column in ("acceleration_m_s2_reduction_percent", "centre_aw_Wk", "force_max_n"):
        assert summary.loc["pid", column] == pytest.approx(np.mean(pid[column].to_numpy()))
    assert summary.loc["pid", "cases"] == 6


def test_by_speed_keeps_the_speeds_apart_over_the_seeds(table):
    rows = table.by_speed()
    pid = table.cases[(table.cases.controller == "pid") & (table.cases.scenario == "fra4")]
    for speed in (30.0, 55.56):
        seeds = pid[pid.speed_m_s == speed]
        row = rows[
            (rows.controller == "pid")
            & (rows.scenario == "fra4")
            & (rows.speed_m_s == speed)
            & (rows.response == "roll_deg")
        ].iloc[0]
        x, red = seeds["roll_deg_rms"].to_numpy(), seeds["roll_deg_reduction_percent"].to_numpy()
        assert row["cases"] == 2 and row["rms_mean"] == pytest.approx(x.mean())
        assert row["reduction_mean"] == pytest.approx(red.mean())
        assert row["reduction_p5"] == pytest.approx(np.percentile(red, 5))
        assert row["rms_p95"] == pytest.approx(np.percentile(x, 95))
    passive = rows[rows.controller == "passive"]
    assert passive["reduction_mean"].isna().all() and (passive["rms_mean"] > 0).all()
    assert len(table.to_dict()["by_speed"]) == len(rows) == 2 * (2 + 2) * 4  # controllers x cases x responses


def test_reduction_follows_from_the_rms_of_passive_and_controller(table):
    c = table.cases
    groups = list(c.groupby(["scenario", "speed_m_s", c.track_seed.fillna(-1)]))
    assert groups  # the loop below checks something
    for (_, speed, seed), group in groups:
        base = group[group.controller == "passive"].iloc[0]
        pid = group[group.controller == "pid"].iloc[0]
        expected = (base.pitch_deg_rms - pid.pitch_deg_rms) / base.pitch_deg_rms * 100
        assert pid.pitch_deg_reduction_percent == pytest.approx(expected)


def test_gains_tuned_on_the_paper_case_are_in_sample_only_there():
    t = league(["paper-sine"], [30.0, 55.56], controllers=["pid"])
    flags = dict(zip(t.cases.speed_m_s, t.cases.in_sample))
    assert flags == {30.0: False, 55.56: True}
    assert t.tuned_on["name"] == "paper-sine"


def test_to_dict_is_json_ready(table):
    import json

    doc = table.to_dict()
    assert doc["schema"] == "railride.league/1"
    text = json.dumps(doc, allow_nan=False)
    assert "ideal_reduction_percent" in text
    pid = next(r for r in doc["controllers"] if r["name"] == "pid")
    assert math.isfinite(pid["roll_deg_ideal_reduction_percent"])


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"scenarios": ["paper-sine", "nowhere"]}, "unknown scenario 'nowhere'"),
        ({"scenarios": []}, "at least one scenario"),
        ({"speeds": [-1.0]}, "speed = -1.0"),
        ({"track_seeds": [-1]}, "track_seed = -1"),
        ({"controllers": ["pid", "skyhoook"]}, "unknown controller 'skyhoook'"),
    ],
)
def test_bad_input_names_the_field(kwargs, message):
    with pytest.raises(ValueError, match=message):
        league(**{"duration": 1.0, **kwargs})


def test_protocol(table, tmp_path):
    fig = table.plot()
    assert fig.axes
    assert len(table.to_pandas()) == len(table.cases)
    paths = table.save(tmp_path / "out")
    assert sorted(p.name for p in paths) == ["league.csv", "league.json", "league.png", "league_comfort.png"]


def test_comfort_chart_draws_into_the_given_axes(table):
    from matplotlib.figure import Figure

    from railride.plots.league import plot_league_comfort

    fig = Figure()
    ax = fig.add_subplot()
    assert plot_league_comfort(table, ax=ax) is fig
    assert len(ax.lines) == len(table.controllers)  # one line per controller, against speed
    with pytest.raises(ValueError, match="index = 'Wz'"):
        plot_league_comfort(table, index="Wz")


def test_hysteresis_plot_has_one_panel_per_suspension():
    from matplotlib.figure import Figure

    import railride as rr
    from railride.plots.comparison import plot_comparison_hysteresis

    comp = rr.compare(rr.scenario("paper-sine", duration=1.0), controllers=["pid", "skyhook"], bounds=False)
    fig = Figure()
    axes = fig.subplots(1, 3)
    assert plot_comparison_hysteresis(comp, ax=axes) is fig
    # passive: the viscous damper's force is -c_sz x' exactly, a line through the origin whose
    # slope, in the panel's kN against m/s, is -c_sz / 1000 (-80 kN s/m for the paper's 8e4 N s/m)
    x, f = axes[0].lines[0].get_data()
    assert np.ptp(x) > 0.01  # the corner moves: the slope is measured, not made up of rounding
    slope = np.polyfit(x, f, 1)
    assert slope[0] == pytest.approx(-rr.VehicleParams.preset("paper").c_sz / 1e3, rel=1e-9)
    assert abs(slope[1]) < 1e-9 * abs(f).max()
    assert axes[0].get_ylabel() == "force at 1R (kN)" and axes[0].get_xlabel() == "deflection rate (m/s)"
    with pytest.raises(ValueError, match="corner = '3R'"):
        plot_comparison_hysteresis(comp, corner="3R")
