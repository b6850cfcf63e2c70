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
    assert doc["settings"]["tuned_alike"]["budget"] == 400 and set(doc["settings"]["tuned_alike"]["runs"]) == {
        "pid",
        "skyhook",
    }


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
