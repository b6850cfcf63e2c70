"""railride study: statistics over tracks, payloads and faults from the command line."""

import json

import pandas as pd
import pytest

from clihelp import PNG, assert_input_error, ok, ok_json, run

SHORT = ("study", "--controllers", "pid", "--track-seed", "0,1", "--speed", "40", "--duration", 1)


def test_study_json_and_table():
    doc = ok_json(*SHORT, "--load", "1,1.3", "--fault", "none,2L-disconnected")
    assert doc["schema"] == "railride.study/1" and doc["runs"] == 2 * 2 * (1 + 2)
    groups = {(g["controller"], g["load"], g["fault"]) for g in doc["results"]}
    assert ("pid", 1.3, "2L-disconnected") in groups and ("passive", 1.0, "none") in groups
    assert doc["settings"]["loads"] == [1.0, 1.3] and doc["failed"] == []
    text = " ".join(ok(*SHORT).stdout.split())
    fragments = (
        "Statistics over 2 track seeds, per speed and condition",
        "N_MV,z centre",
        "p5-p95",
        "passive is always healthy",
    )
    for fragment in fragments:
        assert fragment in text, fragment


def test_study_out_and_resume(tmp_path):
    out = tmp_path / "s"
    first = ok_json(*SHORT, "--out", out)
    names = sorted(p.name for p in out.iterdir())
    assert names == ["runs.csv", "study.json", "study.png", "study_runs.csv", "study_summary.csv"]
    assert (out / "study.png").read_bytes().startswith(PNG)
    assert len(pd.read_csv(out / "study_runs.csv")) == first["runs"]
    again = ok_json(*SHORT, "--out", out, "--resume")
    assert again["runs_evaluated"] == 0 and again["results"] == first["results"]
    assert json.loads((out / "study.json").read_text())["results"] == first["results"]


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--track-seed", "-1"), ("--track-seed",)),
        (("--load", "0"), ("--load", "must be a finite number > 0")),
        (("--fault", "3R-off"), ("--fault = '3R-off'", "allowed 1R, 1L, 2R, 2L")),
        (("--fault", "none,,1R-off"), ("--fault", "empty item")),
        (("--fault", "1R-off@9"), ("--fault", "not within the run")),
        (("--fault", "1R-off", "--damper", "ideal"), ("--fault = '1R-off'", "need MR dampers")),
        (("--controllers", "lqr"), ("unknown controller 'lqr'",)),
        # an unknown name is named first, not through the seeds' check (seeds apply to random tracks)
        (("--scenario", "fra9"), ("--scenario = 'fra9': unknown",)),
        (("--scenario", "fra9", "--track-seed", "0", "--controllers", "pid"), ("--scenario = 'fra9': unknown",)),
        (("--resume",), ("--resume needs --out",)),
    ],
)
def test_study_bad_input(args, fragments):
    assert_input_error(run(*SHORT, *args), *fragments)


def test_study_and_compare_with_accelerometers():
    doc = ok_json(*SHORT, "--sensing", "accelerometers")
    assert doc["settings"]["sensing"] == "accelerometers"
    ideal = ok_json(*SHORT)
    assert doc["results"] != ideal["results"]
    assert_input_error(run(*SHORT, "--sensing", "gyros"), "--sensing = 'gyros'", "ideal, accelerometers")
    assert_input_error(
        run(*SHORT[:2], "pid,hybrid", *SHORT[3:], "--sensing", "accelerometers"), "hybrid reads the bogies"
    )
    cmp = ok_json("compare", "--duration", 1, "--controllers", "sas-attitude,hybrid", "--sensing", "accelerometers")
    assert cmp["settings"]["sensing"]["kind"] == "accelerometers" and "hybrid" in cmp["settings"]["not_run"]
    text = " ".join(ok("compare", "--duration", 1, "--sensing", "accelerometers").stdout.split())
    assert "accelerometers at the corners" in text
    assert_input_error(run("compare", "--duration", 1, "--sensing", "gyros"), "--sensing = 'gyros'")


def test_study_stiffness_tolerance():
    doc = ok_json(*SHORT, "--stiffness", "0.9,1.1")
    assert doc["settings"]["stiffness"] == [0.9, 1.1] and {g["stiffness"] for g in doc["results"]} == {0.9, 1.1}
    assert_input_error(run(*SHORT, "--stiffness", "-1"), "--stiffness", "> 0")


def test_the_documents_record_when_and_by_which_command(tmp_path):
    """compare and study record the date they were made and the command line that made them
    (its options as given), in the printed JSON and in the folder's file alike."""
    import datetime

    out = tmp_path / "s"
    args = ("study", "--controllers", "pid", "--track-seed", 0, "--speed", 30, "--duration", 0.5)
    doc = json.loads(ok(*args, "--format", "json", "--out", out).stdout)
    assert doc["command"] == "railride study --controllers pid --track-seed 0 --speed 30 --duration 0.5"
    made = datetime.datetime.fromisoformat(doc["date"].replace("Z", "+00:00"))
    assert abs((datetime.datetime.now(datetime.timezone.utc) - made).total_seconds()) < 600
    saved = json.loads((out / "study.json").read_text())
    assert saved["command"] == doc["command"] and saved["runs_evaluated"] == doc["runs_evaluated"]
    compared = json.loads(ok("compare", "--controllers", "pid", "--duration", 0.3, "--format", "json").stdout)
    assert compared["command"] == "railride compare --controllers pid --duration 0.3"
    assert compared["date"].endswith("Z")


def test_the_recorded_command_leaves_out_every_output_only_option(tmp_path):
    """The command a result records reproduces it: where and how it was written (--out,
    --report, --figure-format, --dpi) is not part of it (tune kept --report)."""
    out = tmp_path / "t"
    ok("tune", "--controllers", "pid", "--budget", 15, "--duration", 0.2, "--out", out, "--report", tmp_path / "t.html")
    gains = (out / "gains.toml").read_text()
    assert 'command = "railride tune --controllers pid --duration 0.2 --budget 15"' in gains, gains[:600]
