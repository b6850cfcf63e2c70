"""`railride compare`: the JSON contract (railride.comparison/1), the tables, bad input, the --out
folder."""

from __future__ import annotations

import json
import re

import pandas as pd
import pytest
import xarray as xr

from railride.studies.comparison import PAPER_REDUCTION, PAPER_TABLE1
from railride.secondary.control import LABELS, PAPER_CONTROLLERS, GainSet
from railride.output.files import COMPARE_FILES
from clihelp import PNG, assert_input_error, ok, ok_json, run


RESPONSES = ["acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg"]
SHORT = ("compare", "--duration", 2)


def rms(doc, name, response="acceleration_m_s2"):
    row = next(r for r in doc["controllers"] if r["name"] == name)
    return row["metrics"][response]["rms"]


@pytest.fixture(scope="module")
def short_doc() -> dict:
    return ok_json(*SHORT)


@pytest.fixture
def gains_text() -> str:
    """The shipped gains as TOML, with the [pid] kd line written as KD_LINE marks it."""
    return GainSet.default().to_toml()


def pid_kd_line(text: str) -> str:
    """The shipped [pid] kd entry, whatever its value (the first `kd = ` line of to_toml)."""
    return re.search(r"^kd = .*$", text, re.M).group(0)


def write(path, text):
    path.write_text(text, encoding="utf-8")
    return path


# -- the JSON document ------------------------------------------------------------------------------
def test_json_four_controllers_in_order(short_doc):
    doc = short_doc
    assert doc["schema"] == "railride.comparison/1"
    assert [r["name"] for r in doc["controllers"]] == list(PAPER_CONTROLLERS)
    assert [r["label"] for r in doc["controllers"]] == [LABELS[n] for n in PAPER_CONTROLLERS]
    for row in doc["controllers"]:
        assert list(row["metrics"]) == RESPONSES
        for response in RESPONSES:
            m = row["metrics"][response]
            assert set(m) == {"rms", "ptp"} and m["rms"] > 0 and m["ptp"] > 0
            assert row["paper"][response]["rms"] == PAPER_TABLE1[response][row["name"]]
        if row["name"] == "passive":
            assert "reduction_percent" not in row
            assert all("reduction_percent" not in row["paper"][r] for r in RESPONSES)
            assert "voltage_mean_v" not in row["damper"]
        else:
            assert list(row["reduction_percent"]) == RESPONSES
            for response in RESPONSES:
                base = rms(doc, "passive", response)
                expected = (base - row["metrics"][response]["rms"]) / base * 100
                assert row["reduction_percent"][response] == pytest.approx(expected)
                assert row["paper"][response]["reduction_percent"] == PAPER_REDUCTION[response][row["name"]]
            assert 0 <= row["damper"]["voltage_at_max_fraction"] <= 1
        assert row["damper"]["force_rms_n"] > 0 and row["damper"]["travel_max_m"] > 0


def test_json_settings_and_gains(short_doc):
    settings = short_doc["settings"]
    assert settings["scenario"]["name"] == "paper-sine" and settings["scenario"]["duration_s"] == 2.0
    assert settings["damper"] == "railway"
    assert settings["control_rate_hz"] == 1000.0 and settings["dt_s"] == 1e-4
    assert settings["window_s"] == [0.0, 2.0]  # resolved, as in simulate
    assert settings["sensor_noise"] is None
    gains = short_doc["gains"]
    assert gains["source"] == "railride/data/gains.toml"
    assert set(gains) == {"source", "inner", "pid", "sas-attitude", "sas-attitude-ride"}


def test_default_run_is_the_paper_scenario():
    result = run("compare", "--format", "json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["settings"]["scenario"]["name"] == "paper-sine"
    assert doc["settings"]["scenario"]["duration_s"] == 10.0
    assert [r["name"] for r in doc["controllers"]] == list(PAPER_CONTROLLERS)
    assert result.stderr == ""  # no progress when stderr is not a terminal


def test_controllers_pid_gives_passive_and_pid():
    doc = ok_json(*SHORT, "--controllers", "pid")
    assert [r["name"] for r in doc["controllers"]] == ["passive", "pid"]
    assert set(doc["gains"]) == {"source", "inner", "pid"}


def test_controllers_any_order_and_passive_only(short_doc):
    doc = ok_json(*SHORT, "--controllers", "sas-attitude-ride, pid")
    assert [r["name"] for r in doc["controllers"]] == ["passive", "pid", "sas-attitude-ride"]
    assert rms(doc, "pid") == pytest.approx(rms(short_doc, "pid"))
    doc = ok_json(*SHORT, "--controllers", "passive")
    assert [r["name"] for r in doc["controllers"]] == ["passive"]


def test_window_and_sensor_noise_recorded(short_doc):
    doc = ok_json(
        *SHORT, "--controllers", "pid", "--window", "1:", "--sensor-noise", "1e-4,1e-5,1e-3,1e-4", "--seed", 7
    )
    assert doc["settings"]["window_s"] == [1.0, 2.0]
    assert doc["settings"]["sensor_noise"] == {
        "displacement": 1e-4,
        "angle": 1e-5,
        "velocity": 1e-3,
        "angular_rate": 1e-4,
        "seed": 7,
    }
    assert rms(doc, "pid") != rms(short_doc, "pid")


def test_gains_file_changes_the_result(tmp_path, gains_text, short_doc):
    line = pid_kd_line(gains_text)
    changed = write(tmp_path / "gains.toml", gains_text.replace(line, "kd = 100000.0", 1))
    doc = ok_json(*SHORT, "--gains", changed)
    assert doc["gains"]["source"] == str(changed)
    assert doc["gains"]["pid"]["kd"] == 100000.0
    assert rms(doc, "pid") != pytest.approx(rms(short_doc, "pid"), rel=1e-6)
    assert rms(doc, "passive") == rms(short_doc, "passive")
    # the SAS gains are untouched
    assert rms(doc, "sas-attitude") == pytest.approx(rms(short_doc, "sas-attitude"))


def test_damper_option():
    doc = ok_json(*SHORT, "--controllers", "pid", "--damper", "dyke1996")
    assert doc["settings"]["damper"] == "dyke1996"


# -- the tables -------------------------------------------------------------------------------------
def test_table_output(tmp_path):
    result = run(*SHORT, "--gains", write(tmp_path / "g.toml", GainSet.default().to_toml()))
    assert result.exit_code == 0, result.output
    out = result.stdout
    for text in (
        "Ride comparison",
        "Peak-to-peak",
        "asks of its dampers",
        "acceleration (m/s^2)",
        "displacement (m)",
        "pitch (deg)",
        "roll (deg)",
        "red. %",
        "railride",
        "paper",
        "0.3195",
        "1.2001",
        "35.4",
        "RMS force",
        "time at v_max",
        "Passive",
        "SAS (attitude+ride)",
        "ranking",
        "g.toml",
    ):
        assert text in out, text
    assert "…" not in out  # nothing truncated at the default width of a pipe
    assert result.stderr == ""


# -- --out ----------------------------------------------------------------------------------------
def test_out_writes_all_files(tmp_path):
    out = tmp_path / "cmp"
    result = run(*SHORT, "--format", "json", "--out", out)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert sorted(p.name for p in out.iterdir()) == sorted(COMPARE_FILES)
    assert json.loads((out / "compare.json").read_text()) == doc
    with xr.open_dataset(out / "compare.nc", engine="scipy") as ds:
        assert "controller" in ds.dims
        assert [str(c) for c in ds["controller"].values] == list(PAPER_CONTROLLERS)
        assert ds.sizes["time"] == 2001
        assert ds["carbody_bounce"].dims == ("controller", "time")
        assert ds["damper_command_voltage"].sel(controller="passive").isnull().all()
        assert ds["damper_command_voltage"].sel(controller="pid").notnull().all()
    frame = pd.read_csv(out / "compare.csv")
    assert list(frame.columns[:6]) == [
        "controller",
        "time",
        "carbody_acceleration",
        "carbody_bounce",
        "carbody_pitch",
        "carbody_roll",
    ]
    for corner in ("1R", "1L", "2R", "2L"):
        assert f"secondary_damper_force_{corner}" in frame and f"damper_command_voltage_{corner}" in frame
    assert list(frame["controller"].unique()) == list(PAPER_CONTROLLERS)
    assert len(frame) == 4 * 2001
    for name in COMPARE_FILES:
        if name.endswith(".png"):
            assert (out / name).read_bytes()[:8] == PNG, name
    assert [p.name for p in tmp_path.iterdir()] == ["cmp"]  # no staging folder left
    assert "wrote compare.json" in result.stderr


def test_out_passive_only(tmp_path):
    out = tmp_path / "passive"
    assert run(*SHORT, "--controllers", "passive", "--out", out).exit_code == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(COMPARE_FILES)
    assert (out / "voltages.png").read_bytes()[:8] == PNG


# -- bad input --------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--controllers", "pid,lqr"), ("--controllers", "'lqr'", "allowed")),
        (("--controllers", "pid,,sas-attitude"), ("--controllers", "empty item")),
        (("--controllers", ""), ("--controllers",)),
        (("--seed", 3), ("--seed", "--sensor-noise")),
        (("--sensor-noise", "1,2,3"), ("--sensor-noise", "'1,2,3'", "four numbers")),
        (("--sensor-noise", "1,2,3,4,5"), ("--sensor-noise", "four numbers")),
        (("--sensor-noise", "0,0,-1,0"), ("--sensor-noise", "VEL", ">= 0")),
        (("--sensor-noise", "0,x,0,0"), ("--sensor-noise", "ANGLE", "'x'")),
        (("--sensor-noise", "0,0,0,inf"), ("--sensor-noise", "RATE")),
        (("--sensor-noise", "0,0,0,0", "--seed", -1), ("--seed", "-1")),
        (("--damper", "mr9"), ("--damper", "'mr9'")),
        (("--control-rate", 0), ("--control-rate",)),
        (("--control-rate", 300), ("--control-rate", "300", "whole number")),
        (("--speed", -3), ("speed", "-3")),
        (("--window", "5:20"), ("window", "5:20")),
        (("--window", "abc"), ("window",)),
        (("--scenario", "nope"), ("scenario", "'nope'")),
        (("--rail-phase", 10, "--scenario", "bump"), ("rail",)),
        (("--dt", 0.05, "--control-rate", 20), ("dt", "too large")),
        (("--preset", "nope"), ("nope",)),
    ],
)
def test_bad_input(tmp_path, args, fragments):
    out = tmp_path / "out"
    assert_input_error(run(*SHORT, *args, "--out", out), *fragments)
    assert not out.exists() and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "change, fragments",
    [
        (None, ("--gains", "cannot read gains file", "absent.toml")),
        (("KD_LINE", "# kd left out"), ("--gains", "missing entry 'kd' in [pid]")),
        (("KD_LINE", "KD_LINE\nkx = 1.0"), ("--gains", "unknown entry 'kx' in [pid]")),
        (("KD_LINE", 'kd = "lots"'), ("--gains", "'kd' in [pid]", "not a number")),
        (("KD_LINE", "kd = -5.0"), ("--gains", "[pid]", "'kd' = -5.0", ">= 0")),
        (("[pid]", "[pdi]"), ("--gains", "pdi")),
        (("KD_LINE", "kd = ["), ("--gains", "not valid TOML")),
    ],
)
def test_bad_gains_file(tmp_path, gains_text, change, fragments):
    if change is None:
        path = tmp_path / "absent.toml"
    else:
        old, new = change
        line = pid_kd_line(gains_text)
        old, new = old.replace("KD_LINE", line), new.replace("KD_LINE", line)
        assert old in gains_text
        path = write(tmp_path / "gains.toml", gains_text.replace(old, new, 1))
    out = tmp_path / "out"
    result = run(*SHORT, "--gains", path, "--out", out)
    assert_input_error(result, *fragments, str(path))
    assert not out.exists()


def test_bad_input_leaves_existing_out_unchanged(tmp_path):
    out = tmp_path / "existing"
    out.mkdir()
    (out / "compare.json").write_text("old")
    assert_input_error(run(*SHORT, "--controllers", "nope", "--out", out))
    assert_input_error(run(*SHORT, "--seed", 1, "--out", out))
    assert [p.name for p in out.iterdir()] == ["compare.json"]
    assert (out / "compare.json").read_text() == "old"


def test_out_is_a_file(tmp_path):
    target = write(tmp_path / "file.txt", "keep me")
    assert_input_error(run(*SHORT, "--out", target), "not a folder")
    assert target.read_text() == "keep me"


def test_failing_plot_leaves_out_absent(tmp_path, monkeypatch):
    from railride.output import files

    def failing_png(*args, **kwargs):
        raise OSError("disk full (simulated)")

    monkeypatch.setattr(files, "plot_comparison_voltages", failing_png)
    out = tmp_path / "absent"
    assert_input_error(run(*SHORT, "--controllers", "pid", "--out", out), "cannot write the output folder", "simulated")
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_diverged_run_status_2(tmp_path, monkeypatch):
    import importlib

    from railride.errors import DivergenceError

    # the module, not the function of the same name that railride/__init__.py re-exports
    compare_module = importlib.import_module("railride.studies.comparison")

    def boom(*args, **kwargs):
        raise DivergenceError("the simulation diverged (sample 1 at t = 1 s)")

    monkeypatch.setattr(compare_module, "compare", boom)
    out = tmp_path / "absent"
    result = run(*SHORT, "--out", out)
    assert result.exit_code == 2
    assert result.stderr.strip() == "error: the simulation diverged (sample 1 at t = 1 s)"
    assert not out.exists()


# -- trade-offs and bounds ------------------------------------------------------------------------
def test_trade_offs_name_every_response_a_controller_loses(short_doc):
    rows = {r["name"]: r for r in short_doc["controllers"]}
    rms = {n: {k: r["metrics"][k]["rms"] for k in RESPONSES} for n, r in rows.items()}
    tol = short_doc["settings"]["level_tolerance"]
    seen = set()
    for t in short_doc["trade_offs"]:
        a, b = t["controller"], t["than"]
        seen.add((a, b))
        # level: within the tolerance of the larger value; otherwise better or worse
        level = sorted(k for k in RESPONSES if abs(rms[a][k] - rms[b][k]) <= tol * max(rms[a][k], rms[b][k]))
        assert sorted(t["level_on"]) == level
        assert sorted(t["worse_on"]) == sorted(k for k in RESPONSES if rms[a][k] > rms[b][k] and k not in level)
        assert sorted(t["better_on"]) == sorted(k for k in RESPONSES if rms[a][k] < rms[b][k] and k not in level)
    controlled = [n for n in rows if n != "passive"]
    assert seen == {(n, "passive") for n in controlled} | {
        (a, b) for i, a in enumerate(controlled) for b in controlled[i + 1 :]
    }


def test_bounds_are_the_same_gains_on_the_ideal_devices(short_doc):
    from railride.run.simulation import simulate
    from railride.secondary.suspension import Suspension
    from railride.model.track import scenario

    gains = GainSet.default()
    sc = scenario("paper-sine", duration=2.0)
    passive = simulate(sc).metrics().sel(statistic="rms")
    for device in ("ideal-damper", "ideal"):
        m = simulate(sc, suspension=Suspension(device, controller=gains.controller("sas-attitude"))).metrics()
        got = short_doc["bounds"][device]["sas-attitude"]
        for k in RESPONSES:
            assert got["rms"][k] == pytest.approx(float(m.sel(statistic="rms", response=k)), rel=1e-12)
            red = float((passive.sel(response=k) - m.sel(statistic="rms", response=k)) / passive.sel(response=k) * 100)
            assert got["reduction_percent"][k] == pytest.approx(red, rel=1e-9)


def test_compare_table_shows_the_trade_offs_and_the_bounds(short_doc):
    result = run(*SHORT)
    assert result.exit_code == 0, result.stderr
    assert "beside the references" in result.stdout and "ideal damper:" in result.stdout
    # the same gains on ideal devices are references: the MR dampers beat the ideal damper with
    # them on some responses and tracks, so nothing may call them a bound
    text = " ".join(result.stdout.split())
    assert "not bounds" in text and "upper bound" not in text and "best any" not in text
    losing = [t for t in short_doc["trade_offs"] if t["worse_on"]]
    assert losing  # with the shipped gains, PID beats SAS on pitch and loses the rest
    # one line per winner and sets of responses won, lost and level (pairs alike share a line)
    groups = {(t["controller"], tuple(t["better_on"]), tuple(t["worse_on"]), tuple(t["level_on"])) for t in losing}
    assert 0 < result.stdout.count("trade-off:") == len(groups) <= len(losing)
    assert "within 1 % of the larger count as level" in text
    assert "beside the references" not in run(*SHORT, "--no-bounds").stdout


def test_compare_with_a_payload_keeps_the_gains_and_records_the_loaded_vehicle():
    from railride.model.params import VehicleParams

    paper = VehicleParams.preset("paper")
    doc = ok_json("compare", "--duration", 1, "--load", 1.3)
    params = doc["settings"]["vehicle_params"]
    assert params["m_c"] == pytest.approx(1.3 * paper.m_c) and params["m_b"] == paper.m_b
    nominal = ok_json("compare", "--duration", 1)
    assert doc["gains"] == nominal["gains"]  # the gains tuned for the nominal vehicle
    assert doc["controllers"][0]["metrics"] != nominal["controllers"][0]["metrics"]  # a heavier car rides otherwise
    text = ok("compare", "--duration", 1, "--load", 1.3).stdout
    assert "vehicle: paper, load 1.3" in text
    assert doc["settings"]["vehicle"]["load"] == 1.3 and doc["settings"]["vehicle"]["values"] == paper.to_dict()
    simulated = ok_json("simulate", "--duration", 1, "--load", 1.3)
    assert simulated["load_factor"] == 1.3


@pytest.mark.parametrize("value", ["0", "-0.5", "nan"])
def test_a_load_factor_must_be_positive(value):
    for command in ("compare", "simulate"):
        assert_input_error(run(command, "--duration", 1, "--load", value), "--load = ", "must be a finite number > 0")


def test_compare_with_a_fault_prints_the_degradation():
    text = ok("compare", "--duration", 2, "--fault", "1R-off,2L-on@1").stdout
    flat = " ".join(text.split())
    assert "With the faults 1R-off, 2L-on@1 against healthy dampers" in flat and "RMS change %" in flat
    assert "beside the references" in ok("compare", "--duration", 2).stdout and "beside the references" not in text
    doc = ok_json("compare", "--duration", 2, "--fault", "2R-disconnected")
    assert doc["faults"]["faults"] == ["2R-disconnected"] and doc["bounds"] is None
    assert set(doc["faults"]["controllers"]) == {"pid", "sas-attitude", "sas-attitude-ride"}
    # the main table says its runs are faulted, and the paper's healthy table is no reference for them
    assert "the controllers' dampers with the faults 1R-off, 2L-on@1 (passive healthy)" in flat
    assert "beside the paper's Table 1" not in flat and "and healthy dampers" in flat
    assert "no ideal-device references are run" in flat and not doc["paper_case"]


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("--fault", "3R-off"), ("--fault = '3R-off'", "allowed 1R, 1L, 2R, 2L")),
        (("--fault", "1R-stuck"), ("--fault = '1R-stuck'", "allowed off, on, disconnected")),
        (("--fault", "1R-off@9"), ("--fault = '1R-off@9'", "not within the run")),
        (("--fault", "1R-off,1R-on"), ("--fault", "more than one fault")),
        (("--fault", "1R-on", "--damper", "ideal"), ("--fault", "need MR dampers")),
        (("--fault", "1R-off", "--speed", "30,40"), ("--fault", "applies to a single scenario")),
    ],
)
def test_compare_refuses_bad_faults(args, fragments):
    assert_input_error(run("compare", "--duration", 2, *args), *fragments)


@pytest.mark.parametrize(
    "args, paper",
    [
        ((), True),
        (("--speed", "40"), False),
        (("--wavelength", "40"), False),
        (("--load", "1.3"), False),
        (("--scenario", "fra4"), False),
    ],
)
def test_the_papers_table_stands_beside_the_papers_case_only(args, paper):
    doc = ok_json("compare", "--duration", 1, *args)
    assert doc["paper_case"] is paper
    assert len(doc["controllers"]) == len(PAPER_CONTROLLERS)
    assert all((r["paper"] is not None) is paper for r in doc["controllers"])
    text = " ".join(ok("compare", "--duration", 1, *args).stdout.split())
    assert ("beside the paper's Table 1" in text) is paper
    assert ("No published reference exists for this case" in text) is not paper


def test_the_references_switch_and_its_older_spelling():
    """--no-references skips the ideal devices' runs; --no-bounds, its older spelling, does the same."""
    for off in ("--no-references", "--no-bounds"):
        doc = ok_json("compare", "--duration", 0.2, "--controllers", "pid", off)
        assert doc["bounds"] is None
    doc = ok_json("compare", "--duration", 0.2, "--controllers", "pid", "--references")
    assert set(doc["bounds"]) == {"ideal-damper", "ideal"}
