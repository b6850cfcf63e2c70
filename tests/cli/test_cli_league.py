"""railride compare with several scenarios, speeds or track seeds: the league table."""

import json

import pytest

from clihelp import assert_input_error, ok, ok_json, run

SHORT = ("--duration", "1", "--controllers", "pid,skyhook")


def test_several_scenarios_and_speeds_give_a_league_table():
    result = ok("compare", "--scenario", "paper-sine,fra4", "--speed", "30,55.56", *SHORT)
    text = result.stdout
    assert "League table" in text and "Skyhook" in text and "(%)" in text
    assert "Mean over 4 cases" in text
    # the shipped gains: every law tuned alike, and the output says with what budget
    assert "Tuned alike" in " ".join(text.split()) and "Not tuned" not in text


def test_a_law_a_gains_file_did_not_tune_is_named(tmp_path):
    from railride.studies.tuning import tune

    res = tune(("pid",), scenario_options={"duration": 0.5}, n_values=3, budget=5, before_after=False)
    path = tmp_path / "gains.toml"
    path.write_text(res.gains_toml())
    text = ok("compare", "--scenario", "paper-sine", "--speed", "30,40", *SHORT, "--gains", path).stdout
    assert "Not tuned: skyhook" in text  # the untuned law is named, not ranked silently
    flat = " ".join(text.split())
    assert "Tuned alike" in flat and "(runs used: pid 4)" in flat  # the runs the tuned one had


def test_json_has_one_row_per_case_and_controller():
    doc = ok_json("compare", "--scenario", "fra4", "--track-seed", "0,1", *SHORT)
    assert doc["schema"] == "railride.league/1"
    assert [c["name"] for c in doc["controllers"]] == ["passive", "pid", "skyhook"]
    assert len(doc["cases"]) == 2 * 3
    assert doc["settings"]["untuned"] == []
    # random track: the robust set, tuned by the design on 36 runs per gain set, 130 sets a law
    alike = doc["settings"]["tuned_alike"]
    assert alike["budget"] == 130 and alike["runs_per_gain_set"] == 36 and set(alike["runs"]) == {"pid", "skyhook"}
    assert doc["settings"]["gains"].endswith("robust_gains.toml")


def test_out_writes_the_league_files(tmp_path):
    ok("compare", "--scenario", "paper-sine", "--speed", "30,40", *SHORT, "--out", tmp_path / "out")
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "league.csv",
        "league.json",
        "league.png",
        "league_comfort.png",
    ]
    json.loads((tmp_path / "out" / "league.json").read_text())


@pytest.mark.parametrize(
    "extra, words",
    [
        (("--scenario", "paper-sine,nowhere"), ("unknown scenario 'nowhere'",)),
        (("--scenario", "paper-sine,fra4", "--amplitude", "0.02"), ("--amplitude", "single scenario")),
        (("--speed", "30,40", "--no-bounds"), ("--no-bounds",)),
        (("--speed", "30,-40"), ("speed", "-40")),
        (("--scenario", "fra4", "--track-seed", "0,-1"), ("track_seed", "-1")),
        (("--speed", "30,40", "--controllers", "pid,nope"), ("nope", "allowed")),
    ],
)
def test_bad_lists_are_input_errors(extra, words):
    args = [a for a in SHORT if a not in ("--controllers", "pid,skyhook")] if "--controllers" in extra else SHORT
    assert_input_error(run("compare", *args, *extra), *words)


def test_several_loads_make_a_league_table_that_keeps_them_apart():
    args = ("compare", "--speed", "40", "--load", "1,1.3", *SHORT)
    text = ok(*args).stdout
    flat = " ".join(text.split())
    assert "League table" in text and "Mean over 2 cases: paper-sine at 40 m/s, each at loads 1, 1.3" in flat
    assert "This mean pools the loads" in flat and "vehicle: paper, loads 1, 1.3" in flat
    assert "Per scenario, speed and load" in text and "Speeds and loads are kept apart" in flat
    doc = ok_json(*args)
    assert doc["schema"] == "railride.league/1" and doc["settings"]["vehicle"]["load"] == [1.0, 1.3]
    assert sorted({c["load"] for c in doc["cases"]}) == [1.0, 1.3] and len(doc["cases"]) == 2 * 3
    assert sorted({r["load"] for r in doc["by_speed"]}) == [1.0, 1.3]
    # the loads are runs of their own: the heavier carbody rides otherwise
    passive = {c["load"]: c["acceleration_m_s2_rms"] for c in doc["cases"] if c["controller"] == "passive"}
    assert passive[1.0] != passive[1.3]


def test_one_load_is_one_comparison_as_before():
    doc = ok_json("compare", "--duration", "1", "--controllers", "pid", "--no-bounds", "--load", "1.3")
    assert doc["schema"] == "railride.comparison/1" and doc["settings"]["vehicle"]["load"] == 1.3


@pytest.mark.parametrize(
    "load, words",
    [
        ("1,0", ("--load = 0", "must be a finite number > 0")),
        ("1,-1.3", ("--load = -1.3", "must be a finite number > 0")),
        ("1,heavy", ("--load = '1,heavy'", "'heavy' is not a number")),
        ("1,,1.3", ("--load = '1,,1.3'", "an empty item")),
        ("1,1.3,1", ("--load = '1,1.3,1'", "listed twice")),
    ],
)
def test_bad_load_lists_are_input_errors(load, words):
    assert_input_error(run("compare", "--speed", "40", "--load", load, *SHORT), *words)
