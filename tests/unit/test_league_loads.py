"""The league table over several load factors: every case at every load, the loads kept apart
(never pooled into one band), the runs at load 1 those of a league at load 1 alone, and bad
loads refused before any run."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

import railride as rr
from railride.errors import InputError
from railride.studies import league as league_module
from railride.studies.league import league

LOADS = [1.0, 1.3]
#: the shipped paper gains on both tracks: what is compared is the load, not the gains
ARGS = dict(
    scenarios=["paper-sine", "fra4"],
    speeds=[40.0],
    track_seeds=[0, 1],
    controllers=["pid"],
    duration=2.0,
)


@pytest.fixture(scope="module")
def two():
    return league(**ARGS, load=LOADS, gains=rr.GainSet.default())


@pytest.fixture(scope="module")
def one():
    return league(**ARGS, load=1.0, gains=rr.GainSet.default())


def test_every_case_runs_at_every_load_with_a_load_column(two, one):
    cases = two.cases
    assert "load" in cases and set(cases["load"]) == set(LOADS)
    # paper-sine: 1 case, fra4: 2 seeds; each at both loads, passive and pid
    assert len(cases) == 2 * len(one.cases) == (1 + 2) * 2 * 2
    for load in LOADS:
        at = cases[cases["load"] == load]
        assert len(at) == len(one.cases)
        assert sorted(at[at.scenario == "fra4"].track_seed) == [0, 0, 1, 1]
    assert set(one.cases["load"]) == {1.0}
    assert two.settings["vehicle"]["load"] == LOADS and one.settings["vehicle"]["load"] == 1.0
    assert set(two.cases["vehicle"]) == {"paper"}


def test_the_values_at_load_1_are_those_of_a_league_at_load_1(two, one):
    at_1 = two.cases[two.cases["load"] == 1.0].reset_index(drop=True)
    pd.testing.assert_frame_equal(at_1, one.cases)  # the same runs, bit for bit
    by_load = two.by_speed()
    pd.testing.assert_frame_equal(by_load[by_load["load"] == 1.0].reset_index(drop=True), one.by_speed())


def test_by_speed_keeps_each_load_apart(two):
    rows = two.by_speed()
    assert set(rows["load"]) == set(LOADS)
    # controllers x (scenario, speed) x loads x responses
    assert len(rows) == 2 * 2 * 2 * 4
    keys = ["controller", "scenario", "speed_m_s", "response"]
    assert (rows.groupby(keys).size() == len(LOADS)).all()  # one row per load, never one pooled band
    fra4 = rows[rows.scenario == "fra4"]
    assert (fra4["cases"] == 2).all()  # the two seeds, at one load
    for load in LOADS:
        seeds = two.cases[(two.cases.scenario == "fra4") & (two.cases.controller == "pid") & (two.cases.load == load)]
        row = fra4[(fra4.controller == "pid") & (fra4.load == load) & (fra4.response == "pitch_deg")].iloc[0]
        assert row["rms_mean"] == pytest.approx(seeds["pitch_deg_rms"].mean())
        assert row["reduction_p95"] == pytest.approx(np.percentile(seeds["pitch_deg_reduction_percent"], 95))
    doc = two.to_dict()
    assert {r["load"] for r in doc["by_speed"]} == set(LOADS)
    assert {r["load"] for r in doc["cases"]} == set(LOADS)
    json.dumps(doc, allow_nan=False)


def test_a_heavier_carbody_rides_otherwise(two):
    """Physics: 30 % more carbody mass on the same springs and dampers changes the passive
    carbody acceleration on every track; on the random track (broadband) it lowers it."""
    passive = two.cases[two.cases.controller == "passive"].fillna({"track_seed": -1})
    pivot = passive.pivot_table(index=["scenario", "track_seed"], columns="load", values="acceleration_m_s2_rms")
    light, heavy = pivot[1.0], pivot[1.3]
    assert ((heavy - light).abs() / light > 0.005).all(), pivot
    assert (heavy.loc["fra4"] < 0.95 * light.loc["fra4"]).all(), pivot


def test_the_summary_is_the_mean_over_all_cases_and_loads(two):
    summary = two.summary
    assert "load" not in summary
    pid = two.cases[two.cases.controller == "pid"]
    assert summary.loc["pid", "cases"] == 6
    assert summary.loc["pid", "roll_deg_rms"] == pytest.approx(pid["roll_deg_rms"].mean())
    assert "by_speed" in league_module.LeagueTable.summary.__doc__  # it says where the loads are kept apart


def test_the_gains_mismatch_sees_every_load(two, one):
    assert "load 1.3" in two.settings["gains_mismatch"]
    assert "--load 1,1.3" in two.settings["gains_mismatch"]
    assert "load 1.3" not in (one.settings.get("gains_mismatch") or "")


def test_the_document_validates_against_its_schema(two):
    jsonschema = pytest.importorskip("jsonschema")
    from pathlib import Path

    schema = json.loads((Path(__file__).parents[2] / "docs" / "schemas" / "railride.league-1.json").read_text())
    doc = json.loads(json.dumps(two.to_dict(), default=str))
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)


def test_the_comfort_chart_draws_a_line_per_controller_and_load(two):
    from matplotlib.figure import Figure

    from railride.plots.league import plot_league, plot_league_comfort

    fig = Figure()
    ax = fig.add_subplot()
    plot_league_comfort(two, ax=ax)
    assert len(ax.lines) == len(two.controllers) * len(LOADS)
    assert {line.get_label() for line in ax.lines} >= {"PID, load 1", "PID, load 1.3"}
    fig = Figure()
    ax = fig.add_subplot()
    plot_league(two, ax=ax)
    assert "loads 1, 1.3 pooled" in ax.get_title()


@pytest.mark.parametrize(
    "load, words",
    [
        ([], ("load = []", "at least one load factor")),
        ([1.0, 0.0], ("load = 0", "must be a finite number > 0")),
        ([1.0, -1.3], ("load = -1.3", "must be a finite number > 0")),
        (math.nan, ("load = nan", "must be a finite number > 0")),
        ([1.0, math.inf], ("load = inf", "must be a finite number > 0")),
        ("1.3", ("load = '1.3'", "must be a finite number > 0")),
        (True, ("load = True", "must be a finite number > 0")),
        ([1.0, 1.3, 1.0], ("load = [1.0, 1.3, 1.0]", "1 is listed twice")),
    ],
)
def test_bad_loads_are_refused_before_any_run(load, words, monkeypatch):
    def no_run(*args, **kwargs):
        raise AssertionError("a run started before the loads were checked")

    monkeypatch.setattr(league_module, "compare", no_run)
    with pytest.raises(InputError) as info:
        league(["paper-sine"], [30.0, 40.0], load=load, controllers=["pid"], gains=rr.GainSet.default(), duration=2.0)
    for w in words:
        assert w in str(info.value), str(info.value)


def test_a_bad_load_after_good_ones_stops_the_league_before_its_first_run(monkeypatch):
    calls = []
    monkeypatch.setattr(league_module, "compare", lambda *a, **k: calls.append(1))
    with pytest.raises(InputError, match="load = 0"):
        league(["paper-sine"], load=[1.0, 1.3, 0.0], controllers=["pid"], gains=rr.GainSet.default(), duration=2.0)
    assert not calls
