"""`railride tune --start M`: tuning on a measured profile's section, recorded as such, so that a
run on another section of the line is told the tune command for its own (with --start)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from clihelp import assert_input_error, ok, run

TUNE = ("tune", "--controllers", "pid", "--budget", 15, "--values", 3, "--speed", 30, "--duration", 1)


@pytest.fixture(scope="module")
def line(tmp_path_factory):
    folder = tmp_path_factory.mktemp("line")
    s = np.arange(0.0, 1500.0, 0.25)
    zl = 0.003 * np.sin(2 * np.pi * s / 37) + 0.002 * np.sin(2 * np.pi * s / 11.3)
    zr = 0.003 * np.sin(2 * np.pi * s / 37 + 0.4) + 0.001 * np.sin(2 * np.pi * s / 7.1)
    path = folder / "line.csv"
    path.write_text("s,z_L,z_R\n" + "".join(f"{a:.17g},{b:.17g},{c:.17g}\n" for a, b, c in zip(s, zl, zr)))
    out = folder / "tuned"
    ok(*TUNE, "--scenario", f"file:{path}", "--start", 500, "--out", out)
    return path, out


def test_the_section_is_the_one_tuned_on_and_is_recorded(line):
    path, out = line
    record = json.loads((out / "tune.json").read_text())["scenario"]
    assert record["start_m"] == 500.0 and record["source"] == f"{path} from s = 500 m"
    assert record["s_end_m"] == pytest.approx(1500.0 - 0.25 - 500.0)


def test_another_section_is_told_to_tune_with_its_start_and_the_same_is_in_sample(line):
    path, out = line
    args = ("compare", "--controllers", "pid", "--no-references", "--speed", 30, "--duration", 1)
    args += ("--scenario", f"file:{path}", "--gains", out / "gains.toml")
    other = ok(*args, "--start", 900)
    warning = [x for x in other.stderr.splitlines() if x.startswith("warning: ")]
    assert len(warning) == 1 and "(start 900 m)" in warning[0], other.stderr
    assert warning[0].endswith(f"railride tune --scenario file:{path} --speed 30 --duration 1 --start 900")
    assert f"on file:{path} (from s = 500 m) at 30 m/s" in warning[0]
    assert "tuned on another stretch of it (from s = 500 m), at 30 m/s" in " ".join(other.stdout.split())
    same = ok(*args, "--start", 500)
    assert "warning" not in same.stderr and "in-sample" in same.stdout


def test_a_tuning_set_runs_every_member_on_the_section(line, tmp_path):
    path, _ = line
    ok(*TUNE, "--scenario", f"file:{path}", "--start", 250, "--load", "1,1.3", "--out", tmp_path / "set")
    members = json.loads((tmp_path / "set" / "tune.json").read_text())["settings"]["tuning_set"]
    assert [(m["load"], m["start_m"]) for m in members] == [(1.0, 250.0), (1.3, 250.0)]


def test_a_start_too_near_the_end_says_the_latest_start(line):
    path, _ = line
    result = run(*TUNE, "--scenario", f"file:{path}", "--start", 1480)
    assert_input_error(
        result, "--start = 1480 m: the run covers 30.0 m", "the profile runs 19.75 m", "a start of at most 1469.75 m"
    )
