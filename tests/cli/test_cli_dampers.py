"""The damper commands of the `railride` command line: `damper`, `tracking`, and
`simulate --suspension mr`: JSON contracts, bad input, the --out folders."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from clihelp import assert_input_error, ok_json, run


CYCLE_KEYS = {"voltage_v", "force_max_n", "force_min_n", "energy_per_cycle_j"}
METRIC_KEYS = {"rms_error_n", "rms_demand_n", "normalised_rms_error", "window_s"}
DAMPER = ("damper", "--amplitude", 0.01, "--frequency", 2, "--cycles", 2)


# -- damper ---------------------------------------------------------------------------------------
def test_damper_json_one_cycle_per_voltage():
    doc = ok_json(*DAMPER, "--voltage", "0,1,2.25")
    assert list(doc) == ["schema", "railride_version", "versions", "damper", "amplitude_m", "frequency_hz", "cycles"]
    assert doc["schema"] == "railride.damper/1"
    assert doc["damper"]["model"] == "bouc-wen" and doc["damper"]["v_max"] == 2.25
    assert doc["amplitude_m"] == 0.01 and doc["frequency_hz"] == 2.0
    assert [c["voltage_v"] for c in doc["cycles"]] == [0.0, 1.0, 2.25]
    for c in doc["cycles"]:
        assert set(c) == CYCLE_KEYS
        assert all(math.isfinite(v) for v in c.values())
        assert c["force_max_n"] > 0 > c["force_min_n"] and c["energy_per_cycle_j"] > 0
    for key in ("force_max_n", "energy_per_cycle_j"):
        values = [c[key] for c in doc["cycles"]]
        assert values == sorted(values) and values[0] < values[-1], key
    mins = [c["force_min_n"] for c in doc["cycles"]]
    assert mins == sorted(mins, reverse=True)
    # the railway preset: about 1.7 kN at 0 V and 20 kN at 2.25 V (docs/dampers.md, Presets)
    assert 1.2e3 < doc["cycles"][0]["force_max_n"] < 2.5e3
    assert 15e3 < doc["cycles"][-1]["force_max_n"] < 25e3


def test_damper_spencer_and_keywords():
    doc = ok_json(*DAMPER, "--model", "spencer1997", "--voltage", "passive-off, passive-on")
    assert doc["damper"]["model"] == "spencer"
    assert [c["voltage_v"] for c in doc["cycles"]] == [0.0, 2.25]
    assert doc["cycles"][1]["force_max_n"] > doc["cycles"][0]["force_max_n"]


def test_damper_table():
    result = run(*DAMPER, "--voltage", "0,2.25")
    assert result.exit_code == 0, result.output
    for text in ("railway", "voltage (V)", "max force (kN)", "energy per cycle (J)", "2.25"):
        assert text in result.stdout
    assert result.stderr == ""


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--model", "nope", "--voltage", "1"), ("--damper", "nope", "railway")),
        (("--voltage", "3"), ("--voltage", "3", "2.25")),
        (("--voltage", "-0.5"), ("--voltage", "-0.5")),
        (("--voltage", "0,abc"), ("--voltage", "abc")),
        (("--voltage", "0,,1"), ("--voltage",)),
        (("--voltage", "1,1"), ("--voltage", "twice")),
        (("--voltage", "nan"), ("--voltage", "nan")),
        (("--voltage", "1", "--cycles", "1"), ("--cycles", "1")),
    ],
)
def test_damper_bad_input(args, fragments):
    assert_input_error(run(*DAMPER, *args), *fragments)


@pytest.mark.parametrize(
    "option, value",
    [
        ("--amplitude", "-0.01"),
        ("--amplitude", "0"),
        ("--frequency", "0"),
        ("--frequency", "-1"),
        ("--frequency", "inf"),
    ],
)
def test_damper_bad_motion(option, value):
    args = {"--amplitude": "0.01", "--frequency": "1", option: value}
    result = run("damper", "--voltage", "1", *[x for kv in args.items() for x in kv])
    assert_input_error(result, option, value)


def test_library_errors_are_named_by_the_options():
    # the library checks (a cycle too short for the step), the command names its options
    result = run("damper", "--amplitude", 0.01, "--frequency", 1000, "--voltage", "1")
    assert_input_error(result, "--frequency = 1000.0 Hz", "under 100 steps")
    assert_input_error(run("tracking", "--frequency", 200), "--frequency = 200.0 Hz", "under 100 steps")
    assert_input_error(run("tracking", "--G", "-1"), "--G = -1.0", ">= 0 (V/N)")


def test_damper_missing_required_option():
    result = run("damper", "--amplitude", 0.01, "--frequency", 1)
    assert result.exit_code == 2 and "--voltage" in result.output
    assert "Traceback" not in result.output


def test_damper_out_writes_three_files(tmp_path):
    out = tmp_path / "loops"
    result = run(*DAMPER, "--voltage", "0,2.25", "--format", "json", "--out", out)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert sorted(p.name for p in out.iterdir()) == ["cycles.csv", "damper.json", "loops.png"]
    assert json.loads((out / "damper.json").read_text()) == doc
    assert (out / "loops.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    frame = pd.read_csv(out / "cycles.csv")
    assert list(frame.columns) == ["voltage", "time", "x", "xd", "F", "z", "y", "u", "v", "E"]
    assert sorted(frame["voltage"].unique()) == [0.0, 2.25]
    high = frame[frame["voltage"] == 2.25]
    assert high["F"].max() == pytest.approx(doc["cycles"][1]["force_max_n"])
    assert high["x"].max() == pytest.approx(0.01, rel=1e-3)
    assert [p.name for p in tmp_path.iterdir()] == ["loops"]  # no staging folder left


@pytest.mark.parametrize(
    "bad", [("--voltage", "9"), ("--voltage", "1", "--cycles", "0"), ("--voltage", "1", "--model", "x")]
)
def test_damper_failure_leaves_out_absent(tmp_path, bad):
    out = tmp_path / "absent"
    assert_input_error(run(*DAMPER, *bad, "--out", out))
    assert not out.exists() and list(tmp_path.iterdir()) == []


# -- tracking -------------------------------------------------------------------------------------
def test_tracking_json_sine():
    doc = ok_json("tracking", "--cycles", 2)
    assert list(doc) == [
        "schema",
        "railride_version",
        "versions",
        "damper",
        "desired",
        "amplitude_n",
        "frequency_hz",
        "stroke_m",
        "B",
        "G_v_per_n",
        "metrics",
    ]
    assert doc["schema"] == "railride.tracking/1"
    assert doc["desired"] == "sine" and doc["amplitude_n"] == 10e3 and doc["frequency_hz"] == 1.0
    assert doc["stroke_m"] == 0.02 and doc["B"] == 1.0
    assert doc["G_v_per_n"] > 0  # the damper's default gain
    m = doc["metrics"]
    assert set(m) == METRIC_KEYS
    assert math.isfinite(m["normalised_rms_error"]) and 0 < m["normalised_rms_error"] < 1
    assert m["normalised_rms_error"] == pytest.approx(m["rms_error_n"] / m["rms_demand_n"])
    assert m["rms_demand_n"] == pytest.approx(10e3 / math.sqrt(2), rel=1e-3)
    assert m["window_s"] == [1.0, 2.0]


def test_tracking_gains_and_sawtooth():
    doc = ok_json(
        "tracking",
        "--desired",
        "sawtooth",
        "--cycles",
        2,
        "--B",
        0.5,
        "--G",
        0.002,
        "--frequency",
        2,
        "--amplitude",
        5000,
        "--model",
        "dyke1996",
    )
    assert doc["desired"] == "sawtooth" and doc["B"] == 0.5 and doc["G_v_per_n"] == 0.002
    assert doc["metrics"]["window_s"] == [0.5, 1.0]
    assert math.isfinite(doc["metrics"]["normalised_rms_error"])


def test_tracking_table():
    result = run("tracking", "--cycles", 2)
    assert result.exit_code == 0, result.output
    for text in ("RMS tracking error (N)", "RMS demand (N)", "normalised error", "B (-)", "G (V/N)"):
        assert text in result.stdout


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--desired", "square"), ("--desired", "square", "sawtooth")),
        (("--amplitude", "0"), ("--amplitude",)),
        (("--amplitude", "-5"), ("--amplitude", "-5")),
        (("--frequency", "0"), ("--frequency",)),
        (("--cycles", "1"), ("--cycles", "1")),
        (("--damper", "magic"), ("--damper", "magic")),
        (("--B", "-1"), ("--B", "-1")),
        (("--G", "nan"), ("--G", "nan")),
        (("--stroke", "0"), ("--stroke",)),
    ],
)
def test_tracking_bad_input(args, fragments):
    assert_input_error(run("tracking", *args), *fragments)


def test_tracking_out_writes_three_files(tmp_path):
    out = tmp_path / "track"
    result = run("tracking", "--cycles", 2, "--format", "json", "--out", out)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert sorted(p.name for p in out.iterdir()) == ["tracking.csv", "tracking.json", "tracking.png"]
    assert json.loads((out / "tracking.json").read_text()) == doc
    assert (out / "tracking.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    header = (out / "tracking.csv").read_text().split("\n", 1)[0].split(",")
    assert header[0] == "time" and {"F", "desired_force", "u", "v"} <= set(header)
    assert [p.name for p in tmp_path.iterdir()] == ["track"]


def test_tracking_failure_leaves_out_absent(tmp_path):
    out = tmp_path / "absent"
    assert_input_error(run("tracking", "--desired", "square", "--out", out))
    assert not out.exists() and list(tmp_path.iterdir()) == []


# -- simulate --suspension --------------------------------------------------------------------------
def test_simulate_mr_json():
    doc = ok_json("simulate", "--suspension", "mr", "--voltage", 2.25, "--duration", 1)
    assert doc["schema"] == "railride.simulation/1"
    assert doc["suspension"] == {"type": "mr", "damper": "railway", "voltage_v": 2.25}
    assert list(doc).index("suspension") == list(doc).index("vehicle_preset") + 1
    assert doc["metrics"]
    for values in doc["metrics"].values():
        assert math.isfinite(values["rms"]) and values["rms"] > 0


def test_simulate_passive_and_mr_defaults():
    passive = ok_json("simulate", "--duration", 1)
    assert passive["suspension"] == {"type": "passive"}
    off = ok_json("simulate", "--suspension", "mr", "--damper", "dyke1996", "--duration", 1)
    assert off["suspension"] == {"type": "mr", "damper": "dyke1996", "voltage_v": 0.0}
    on = ok_json("simulate", "--suspension", "mr", "--voltage", "passive-on", "--duration", 1)
    assert on["suspension"]["voltage_v"] == 2.25
    # a stiffer damper changes the ride
    assert on["metrics"]["displacement_m"] != passive["metrics"]["displacement_m"]


def test_simulate_table_mentions_suspension():
    result = run("simulate", "--suspension", "mr", "--voltage", 1, "--duration", 1)
    assert result.exit_code == 0, result.output
    assert "suspension MR, railway dampers at 1 V" in result.stdout
    assert "suspension passive" in run("simulate", "--duration", 1).stdout


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--voltage", "1"), ("--voltage", "--suspension mr")),
        (("--damper", "railway"), ("--damper", "--suspension mr")),
        (("--suspension", "semi"), ("--suspension", "semi")),
        (("--suspension", "mr", "--damper", "nope"), ("--damper", "nope")),
        (("--suspension", "mr", "--voltage", "2.5"), ("--voltage", "2.5")),
        (("--suspension", "mr", "--voltage", "high"), ("--voltage", "high")),
    ],
)
def test_simulate_suspension_bad_input(tmp_path, args, fragments):
    out = tmp_path / "absent"
    assert_input_error(run("simulate", "--duration", 1, *args, "--out", out), *fragments)
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_simulate_mr_out(tmp_path):
    out = tmp_path / "mr"
    result = run("simulate", "--suspension", "mr", "--voltage", 1, "--duration", 1, "--out", out)
    assert result.exit_code == 0, result.output
    header = (out / "ride.csv").read_text().split("\n", 1)[0].split(",")
    assert "damper_voltage_1R" in header and "damper_hysteretic_z_2L" in header
    assert json.loads((out / "metrics.json").read_text())["suspension"]["type"] == "mr"


# -- failures after the run -------------------------------------------------------------------------
def test_diverged_rig_run_status_2(tmp_path, monkeypatch):
    from railride.run import rig
    from railride.errors import DivergenceError

    def boom(*args, **kwargs):
        raise DivergenceError("the damper rig run diverged: a state stopped being finite")

    monkeypatch.setattr(rig, "cycles", boom)
    out = tmp_path / "absent"
    result = run(*DAMPER, "--voltage", "1", "--out", out)
    assert result.exit_code == 2
    assert result.stderr.strip() == "error: the damper rig run diverged: a state stopped being finite"
    assert "Traceback" not in result.output and not out.exists()


def test_failing_plot_leaves_out_absent(tmp_path, monkeypatch):
    from railride.output import files

    def failing_png(*args, **kwargs):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(files, "plot_tracking", failing_png)
    out = tmp_path / "absent"
    result = run("tracking", "--cycles", 2, "--out", out)
    assert_input_error(result, "cannot write the output folder", "simulated")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_out_replaces_own_files_keeps_others(tmp_path):
    out = tmp_path / "existing"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "damper.json").write_text("old")
    assert run(*DAMPER, "--voltage", "1", "--out", out).exit_code == 0
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "damper.json").read_text())["schema"] == "railride.damper/1"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["existing"]
