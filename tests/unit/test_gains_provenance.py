"""Gains that know where they came from: the vehicle, load, scenarios and speeds a gains file
was tuned on ([provenance], written by `railride tune`), the one line a run with gains tuned for
another case gets (`GainSet.mismatch`, on stderr and in the result's settings), and the
provenance kept by `GainSet.to_toml` while the run keys (`key_text`) stay as they were."""

from __future__ import annotations

import datetime
import hashlib
import math

import pytest

import railride as rr
from clihelp import ok, ok_json
from railride.model.params import VehicleParams, vehicle_record
from railride.secondary.control import GainSet
from railride.secondary.provenance import provenance_toml, tune_command
from railride.studies.tuning import tuning_set, tune

#: GainSet.default().key_text() before gains files kept their provenance (the run keys of the
#: shipped gains, which every resumable run table holds)
DEFAULT_KEY_SHA256 = "13b4583bff8807dc0db36f51810f46fd523ff4899fe76441e5099de60d4e844b"
REFERENCE_KEY_SHA256 = "601b68538fbac1ceabf8d239e5c515010ae0063c30446f77d48549f6d5908eae"
SHORT = {"duration": 0.5}


def record(name: str = "paper", load=1.0) -> dict:
    return vehicle_record(VehicleParams.preset(name), None, load)


def track(name: str = "paper-sine", **options) -> dict:
    return rr.scenario(name, **options).describe()


@pytest.fixture(scope="module")
def tuned():
    """A tiny tuning of PID on the CRH380A-type car: the gains file it writes, read back."""
    res = tune(["pid"], budget=5, n_values=3, scenario_options=SHORT, before_after=False, vehicle="crh380a")
    return res, GainSet.from_toml(res.gains_toml(command="railride tune"), source="tuned.toml")


@pytest.fixture(scope="module")
def robust():
    """A tiny robust tuning over two FRA class 4 tracks and two loads."""
    over = tuning_set("fra4", track_seeds=[0, 1], loads=[1.0, 1.3], duration=0.5)
    res = tune(["pid"], over=over, budget=5, n_values=3)
    return res, GainSet.from_toml(res.gains_toml(), source="robust.toml")


# -- what railride tune writes ---------------------------------------------------------------------
def test_tune_records_the_vehicle_load_scenarios_and_speeds(tuned):
    res, gains = tuned
    p = gains.provenance
    assert p["vehicle"] == "crh380a" and p["load"] == 1.0
    # TOML keeps no None: the fields the vehicle leaves out (EI_c: it bends at a given f_bend)
    assert p["vehicle_values"] == {k: v for k, v in VehicleParams.preset("crh380a").to_dict().items() if v is not None}
    assert p["scenarios"] == ["paper-sine"] and p["speeds_m_s"] == [55.56]
    assert p["scenario_record"] == res.scenario  # the existing keys stay
    assert p["controllers"] == ["pid"] and p["budget"] == 5 and "pid" in p["studies"]
    text = res.gains_toml()
    assert "# vehicle: crh380a, load 1\n" in text
    # its own case: nothing to say; the paper's vehicle: one line with the command for it
    assert gains.mismatch(res.settings["vehicle"], res.scenario) is None
    line = gains.mismatch(record("paper"), res.scenario)
    assert line is not None and "\n" not in line and "vehicle crh380a" in line and "vehicle paper" in line
    assert line.endswith("railride tune --duration 0.5")  # the paper's vehicle is the default


def test_a_robust_tuning_records_its_tracks_and_loads_and_any_of_them_matches(robust):
    _, gains = robust
    p = gains.provenance
    assert p["vehicle"] == "paper" and p["load"] == [1.0, 1.3]
    assert p["scenarios"] == ["fra4"] and p["speeds_m_s"] == [55.56]
    assert len(p["tuning_set"]) == 4
    runs = [track("fra4", seed=s, duration=0.5) for s in (0, 1)]
    assert gains.mismatch(record("paper", [1.0, 1.3]), runs) is None
    assert gains.mismatch(record("paper", 1.3), runs[1]) is None
    # what it spans: another seed of the spectrum at its speed, a load between its loads
    assert gains.mismatch(record("paper", 1.15), track("fra4", seed=7, duration=0.5)) is None
    line = gains.mismatch(record("paper", [1.0, 1.5]), [*runs, track("fra4", seed=2, duration=0.5, speed=60.0)])
    assert "load 1.5" in line and "track fra4 (speed 60 m/s" in line
    assert "railride tune --load 1,1.5 --scenario fra4 --speed 55.56 --track-seed 0,1,2 --duration 0.5" in line
    assert "(and one tuning each for speed 60 m/s); " in line
    # random track: a tuning on its seeds fits them; a design judges on seeds it never tuned on
    assert line.endswith("; or, for gains judged on seeds they were not tuned on: railride design --load 1,1.5 "
                         "--track fra4 --speed 55.56,60")  # fmt: skip


def check_schema(doc: dict) -> None:
    """``doc`` validates against its schema in docs/schemas (the settings' gains_mismatch too)."""
    import json
    from pathlib import Path

    jsonschema = pytest.importorskip("jsonschema")
    name = doc["schema"].replace("/", "-")
    schema = json.loads((Path(__file__).parents[2] / "docs" / "schemas" / f"{name}.json").read_text())
    jsonschema.validate(json.loads(json.dumps(doc, default=str)), schema, cls=jsonschema.Draft202012Validator)
    assert "gains_mismatch" in schema["properties"]["settings"]["properties"]


def test_what_tune_writes_today_is_what_the_shipped_file_was_given_by_hand():
    import tomllib

    from railride.studies.tune_result import TuneResult

    paper = TuneResult(GainSet.reference(), scenario=track(), settings={"vehicle": record()})
    written = tomllib.loads("\n".join(paper._case_lines()))
    shipped = GainSet.default().provenance
    assert written == {k: shipped[k] for k in written} and set(written) == {
        "vehicle",
        "load",
        "scenarios",
        "speeds_m_s",
    }


# -- the shipped gains -----------------------------------------------------------------------------
def test_the_shipped_gains_say_they_were_tuned_on_the_papers_vehicle_and_sine():
    p = GainSet.default().provenance
    assert p["vehicle"] == "paper" and p["load"] == 1.0
    assert p["scenarios"] == ["paper-sine"] and p["speeds_m_s"] == [55.56]
    assert p["scenario_record"]["name"] == "paper-sine" and p["scenario_record"]["speed_m_s"] == 55.56
    assert p["budget"] == 400 and p["studies"]["pid"]["runs"] == 388  # the keys it had


def test_key_text_is_unchanged_and_holds_no_provenance():
    for gains, sha in ((GainSet.default(), DEFAULT_KEY_SHA256), (GainSet.reference(), REFERENCE_KEY_SHA256)):
        key = gains.key_text()
        assert hashlib.sha256(key.encode()).hexdigest() == sha  # the shipped gains' numbers too
        assert "provenance" not in key


# -- the line, in the library ----------------------------------------------------------------------
def test_the_papers_own_case_has_no_line():
    gains = GainSet.default()
    assert gains.mismatch(record(), track()) is None
    assert gains.mismatch(None, track(duration=0.5)) is None  # any duration of the same track
    assert gains.mismatch(record(), track(), ["passive", "passive-on"]) is None  # nothing reads the gains


@pytest.mark.parametrize(
    "vehicle, scenario, fragments, command",
    [
        (record("crh380a"), track(), ["vehicle crh380a"], "railride tune --vehicle crh380a"),
        (record(load=1.3), track(), ["load 1.3"], "railride tune --load 1.3"),
        (
            record(),
            track("fra4", speed=60.0),
            ["track fra4 (speed 60 m/s)"],
            "railride tune --scenario fra4 --speed 60",
        ),
        (
            record("crh380a", 1.3),
            track("fra4", speed=60.0),
            ["vehicle crh380a, load 1.3, track fra4"],
            "railride tune --vehicle crh380a --load 1.3 --scenario fra4 --speed 60",
        ),
        (
            record(),
            track(speed=40.0, amplitude=0.02),
            ["speed 40 m/s; amplitude 0.02 m"],
            "--speed 40 --amplitude 0.02",
        ),
    ],
)
def test_another_vehicle_load_or_track_has_one_line_with_the_tune_command(vehicle, scenario, fragments, command):
    line = GainSet.default().mismatch(vehicle, scenario)
    assert line is not None and "\n" not in line
    assert line.startswith("the gains railride/data/gains.toml were tuned for vehicle paper, load 1, on paper-sine")
    for fragment in fragments:
        assert fragment in line, line
    assert line.endswith(command) or command in line, line


def test_a_study_over_loads_and_tracks_has_one_line_of_what_differs():
    tracks = [track("fra4", seed=s, speed=v) for s in range(10) for v in (30.0, 40.0)]
    line = GainSet.default().mismatch(record(load=[1.0, 1.3]), tracks)
    assert "\n" not in line and line.count("railride tune") == 1
    assert "load 1.3" in line and "load 1," not in line.split("; this run has ")[1].split(";")[0]
    assert "--load 1,1.3 --scenario fra4 --speed 30 --track-seed 0,1,2,3,4,5,6,7,8,9" in line
    assert "(and one tuning each for speed 40 m/s); " in line
    assert line.endswith("railride design --load 1,1.3 --track fra4 --speed 30,40")


def test_gains_without_a_vehicle_are_taken_as_tuned_on_the_papers_vehicle_at_load_1():
    text = GainSet.default().to_toml()
    for key in ("vehicle", "load", "scenarios", "speeds_m_s"):
        text = "\n".join(line for line in text.splitlines() if not line.startswith(f"{key} = "))
    old = GainSet.from_toml(text, source="old.toml")
    assert "vehicle" not in old.provenance
    assert old.mismatch(record(), track()) is None
    line = old.mismatch(record("manchester-1"), track())
    assert "vehicle paper, load 1 (assumed: the file names no vehicle)" in line
    assert line.endswith("railride tune --vehicle manchester-1")
    # gains with no provenance at all record no tuning: nothing to say
    assert GainSet.reference().mismatch(record("crh380a", 1.3), track("fra4")) is None


def test_a_vehicle_is_matched_by_its_values_and_a_file_names_itself():
    gains = GainSet.default()
    paper = VehicleParams.preset("paper")
    same = vehicle_record(paper, "my_paper.toml")  # a file holding the paper's values
    assert gains.mismatch(same, track()) is None
    heavier = vehicle_record(paper.replace(m_c=4.2e4), "heavy car.toml")
    assert gains.mismatch(heavier, track()).endswith("railride tune --vehicle 'heavy car.toml'")
    assert tune_command(vehicle_record(paper.replace(m_c=4.2e4))) == "railride tune --vehicle FILE.toml"


# -- the line in the results ---------------------------------------------------------------------
@pytest.mark.parametrize(
    "options, command",
    [
        ({}, None),
        ({"vehicle": "crh380a"}, "railride tune --vehicle crh380a --duration 0.2"),
        ({"load": 1.3}, "railride tune --load 1.3 --duration 0.2"),
        ({"scenario": "fra4", "gains": "paper"}, "railride tune --scenario fra4 --duration 0.2"),
        ({"scenario": "fra4"}, None),  # the robust set, tuned on fra4 and fra5 at 30-70 m/s, covers it
    ],
)
def test_compare_records_the_line_in_its_settings(options, command):
    scenario = rr.scenario(options.pop("scenario", "paper-sine"), duration=0.2)
    if "gains" in options:
        options["gains"] = GainSet.named(options["gains"])
    settings = rr.compare(scenario, controllers=["pid"], bounds=False, **options).to_dict()["settings"]
    if command is None:
        assert "gains_mismatch" not in settings  # the paper's case: its document as it was
    else:
        assert command in settings["gains_mismatch"]
        check_schema(rr.compare(scenario, controllers=["pid"], bounds=False, **options).to_dict())
    passive = rr.compare(scenario, controllers=["passive"], bounds=False, **options).settings
    assert "gains_mismatch" not in passive  # no gains run


def test_study_sweep_and_league_record_one_line():
    from railride.studies.league import league
    from railride.studies.study import study
    from railride.studies.sweep import grid, run_sweep

    res = study(["pid"], scenario="paper-sine", loads=[1.0, 1.3], duration=0.2)
    assert res.settings["gains_mismatch"].endswith("railride tune --load 1,1.3 --duration 0.2")
    assert "this run has load 1.3; " in res.settings["gains_mismatch"]
    sweep = run_sweep(grid(["pid"], speed=[40.0, 55.56], duration=0.2), comfort=False)
    line = sweep.settings["gains_mismatch"]
    assert "track paper-sine (speed 40 m/s)" in line and line.endswith("railride tune --speed 40 --duration 0.2")
    assert "gains_mismatch" not in run_sweep(grid(["pid"], duration=0.2), comfort=False).settings
    # several tracks off: named in the grid's order, the same line in every process (not a set's order)
    three = run_sweep(grid(["pid"], speed=[50.0, 30.0, 40.0], duration=0.2), comfort=False).settings["gains_mismatch"]
    assert "(speed 50, 30, 40 m/s)" in three
    assert three.endswith("railride tune --speed 50 --duration 0.2 (and one tuning each for speed 30, 40 m/s)")
    table = league(["paper-sine"], speeds=[40.0, 55.56], controllers=["pid"], duration=0.2, comfort=False)
    assert table.to_dict()["settings"]["gains_mismatch"] == line
    for doc in (res.to_dict(), sweep.to_dict(), table.to_dict()):
        check_schema(doc)


def test_the_cli_warns_with_one_line_on_stderr():
    plain = ok("compare", "--duration", 0.2, "--controllers", "pid", "--no-bounds")
    assert "warning" not in plain.stderr
    result = ok("compare", "--duration", 0.2, "--controllers", "pid", "--no-bounds", "--vehicle", "crh380a")
    lines = [line for line in result.stderr.splitlines() if line.startswith("warning: ")]
    assert len(lines) == 1 and "tuned for vehicle paper" in lines[0]
    assert lines[0].endswith("tune for it with: railride tune --vehicle crh380a --duration 0.2")
    doc = ok_json("compare", "--duration", 0.2, "--controllers", "pid", "--no-bounds", "--load", "1.3")
    assert doc["settings"]["gains_mismatch"].endswith("railride tune --load 1.3 --duration 0.2")


# -- to_toml keeps the provenance ------------------------------------------------------------------
def test_to_toml_keeps_the_provenance(tmp_path):
    shipped = GainSet.default()
    path = tmp_path / "gains.toml"
    path.write_text(shipped.to_toml(), encoding="utf-8")
    back = GainSet.load(path)
    assert back.provenance == shipped.provenance and back == GainSet.from_toml(path.read_text(), source=str(path))
    assert all(back.table(t) == shipped.table(t) for t in GainSet.TABLES)
    assert "[provenance.studies.sas-attitude]" in path.read_text()
    bare = shipped.to_toml(provenance=False)
    assert "provenance" not in bare and GainSet.from_toml(bare).provenance == {}
    assert GainSet.reference().to_toml() == GainSet.reference().to_toml(provenance=False)  # none to keep


def test_a_tuned_file_round_trips_through_to_toml(tuned, robust):
    for _, gains in (tuned, robust):
        again = GainSet.from_toml(gains.to_toml())
        assert again.provenance == gains.provenance


def test_provenance_toml_writes_every_toml_value():
    import tomllib

    provenance = {
        "text": 'quotes " and \\ and\ttabs, é, \U0001f686, \x7f',
        "count": 3,
        "x": 0.1,
        "big": 1e300,
        "inf": math.inf,
        "flag": False,
        "when": datetime.datetime(2026, 1, 2, 3, 4, 5, tzinfo=datetime.timezone.utc),
        "day": datetime.date(2026, 1, 2),
        "gone": None,
        "list": [1.0, "a", [2, 3], {"k": 1}],
        "flat": {"name": "fra4", "seed": 2**63},
        "odd key": 1,
        "nested": {"a": {"b": {"entries": ["x"], "v": -0.0}}, "c": 1},
        "wide": {f"k{i}": float(i) for i in range(20)},
    }
    text = provenance_toml(provenance)
    back = tomllib.loads(text)["provenance"]
    expected = {k: v for k, v in provenance.items() if v is not None}
    assert back == expected
    assert '"odd key" = 1' in text and "[provenance.nested.a.b]" in text and "[provenance.wide]" in text


def test_the_same_name_with_other_values_says_which():
    values = {**{k: v for k, v in VehicleParams.preset("paper").to_dict().items() if v is not None}, "m_c": 1.0}
    inline = "{" + ", ".join(f"{k} = {v!r}" for k, v in values.items()) + "}"
    text = GainSet.default().to_toml().replace('vehicle = "paper"\n', f'vehicle = "paper"\nvehicle_values = {inline}\n')
    line = GainSet.from_toml(text).mismatch(record(), track())
    assert "this run has vehicle paper (other values: m_c); tune for it with: railride tune" in line


def test_gains_tuned_on_the_rigid_car_say_so_on_the_car_that_bends():
    bending = VehicleParams.preset("paper").replace(L_c=24.0, f_bend=10.0)
    line = GainSet.default().mismatch(vehicle_record(bending, "paper"), track())
    assert line is not None and "L_c" in line and "f_bend" in line
    assert GainSet.default().mismatch(record(), track()) is None


@pytest.mark.parametrize(
    "args, command",
    [
        (("study", "--scenario", "paper-sine", "--load", "1,1.3"), "railride tune --load 1,1.3 --duration 0.2"),
        (("pareto", "--samples", 4, "--load", 1.3), "railride tune --load 1.3 --duration 0.2"),
        (("sweep", "--speed", "40,55.56"), "railride tune --speed 40 --duration 0.2"),
        (("compare", "--speed", "40,55.56"), "railride tune --speed 40 --duration 0.2"),  # the league table
    ],
)
def test_the_studies_warn_with_one_line_over_all_their_runs(args, command):
    controllers = ("--suspension", "pid") if args[0] == "sweep" else ("--controllers", "pid")
    if args[0] == "pareto":
        controllers = ()
    result = ok(*args, "--duration", 0.2, *controllers)
    lines = [line for line in result.stderr.splitlines() if line.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].endswith(f"tune for it with: {command}"), result.stderr


def test_a_run_says_whether_its_track_was_in_the_tuning_set():
    """The shipped robust gains were tuned on fra4 and fra5, seeds 1-3, at 30, 50 and 70 m/s,
    20 s runs (their [provenance] tuning set): a 10-s run on fra4 seed 1 at 50 m/s covers half
    of a tuning run's rail (in-sample), at 40 m/s the same rail at a new speed, seed 7 a rail
    tuning never ran on; a 40-s run is a longer realisation, another rail."""
    from railride.model.track import scenario
    from railride.secondary.provenance import HELD_OUT, IN_SAMPLE, SAME_TRACK, judged_on

    robust = GainSet.robust()
    tuned = robust.provenance["tuning_set"]
    assert {(t["name"], t["seed"], t["speed_m_s"]) for t in tuned} >= {("fra4", 1, 50.0), ("fra5", 3, 70.0)}

    def kind(seed, speed, duration=10.0, name="fra4"):
        return judged_on(robust, scenario(name, seed=seed, speed=speed, duration=duration).describe())[0]

    assert kind(1, 50.0) == IN_SAMPLE
    assert kind(3, 70.0, name="fra5") == IN_SAMPLE
    assert kind(1, 40.0) == SAME_TRACK
    assert kind(7, 50.0) == HELD_OUT
    assert kind(1, 50.0, duration=40.0) == HELD_OUT  # 2,000 m of rail do not hold 40 s: 2,100 m
    held = scenario("fra4", seed=7, speed=50.0, duration=1.0)
    assert rr.compare(held, controllers=("pid",), bounds=False).in_sample is False
    seen = scenario("fra4", seed=1, speed=50.0, duration=1.0)
    doc = rr.compare(seen, controllers=("pid",), bounds=False).to_dict()
    assert doc["tuning"]["in_sample"] and doc["tuning"]["track"]["kind"] == IN_SAMPLE
    # gains tuned on the paper's sine, judged on it and on a random track
    paper = GainSet.default()
    assert judged_on(paper, scenario("paper-sine").describe())[0] == IN_SAMPLE
    assert judged_on(paper, scenario("fra4", seed=1).describe())[0] == HELD_OUT


def test_a_run_on_a_measured_line_overlaps_the_sections_tuning_ran_on_or_not():
    """A design tunes on sections of a measured line; a run's record names its start only in
    words, but its s_end_m is the file's end less its start. Tuned on the section from s = 160 m
    (40 m/s x 4 s), a run from s = 0 at 40 m/s is held out for 4 s (0-160 m) and in-sample for
    5 s (0-200 m); at 30 m/s for 6 s (0-180 m), the same rail at a new speed."""
    from types import SimpleNamespace

    from railride.secondary.provenance import HELD_OUT, IN_SAMPLE, SAME_TRACK, judged_on

    line = {"name": "file:line.csv", "profile": "measured"}
    tuned = {**line, "speed_m_s": 40.0, "duration_s": 4.0, "source": "line.csv from s = 160 m", "rows": 79360}
    gains = SimpleNamespace(provenance={"tuning_set": [{**tuned, "s_end_m": 19839.75, "load": 1.0}]})

    def run(speed, duration):
        record = {**line, "speed_m_s": speed, "duration_s": duration, "source": "line.csv", "rows": 80000}
        return judged_on(gains, {**record, "s_end_m": 19999.75})

    assert run(40.0, 4.0)[0] == HELD_OUT and "another stretch of it, at 40 m/s" in run(40.0, 4.0)[1]
    assert run(40.0, 5.0)[0] == IN_SAMPLE
    assert run(30.0, 6.0)[0] == SAME_TRACK
    assert run(30.0, 5.0)[0] == HELD_OUT  # 0-150 m
