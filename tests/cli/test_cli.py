"""The `railride` command line: output formats, error handling, the --out folder."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
import xarray as xr

from clihelp import assert_input_error, ok, run


METRIC_KEYS = {"acceleration_m_s2", "displacement_m", "pitch_deg", "roll_deg"}
MODE_KEYS = {"label", "frequency_hz", "damped_frequency_hz", "damping_ratio"}


def write_track(path, rows):
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@pytest.fixture
def good_track(tmp_path):
    s = np.linspace(0.0, 200.0, 401)
    rows = ["s [m],z_L [m],z_R [m]"] + [f"{x:.3f},{0.01 * math.sin(x / 10):.6f},{0.0:.1f}" for x in s]
    return write_track(tmp_path / "track.csv", rows)


# -- modes ----------------------------------------------------------------------------------------
def test_modes_json():
    """A ``railride.modes/1`` document: the vehicle's record and its nine modes."""
    result = run("modes", "--format", "json")
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert list(doc) == ["schema", "railride_version", "versions", "vehicle", "modes"]
    assert doc["schema"] == "railride.modes/1"
    assert (doc["vehicle"]["name"], doc["vehicle"]["load"]) == ("paper", 1.0)
    modes = doc["modes"]
    assert isinstance(modes, list) and len(modes) == 9
    for m in modes:
        assert set(m) == MODE_KEYS
        assert isinstance(m["label"], str) and m["label"]
        assert m["frequency_hz"] > 0 and m["damped_frequency_hz"] > 0
        assert 0 < m["damping_ratio"] < 1
    freqs = [m["frequency_hz"] for m in modes]
    assert freqs == sorted(freqs)
    assert result.stderr == ""


def test_modes_table_and_preset():
    result = run("modes", "--preset", "paper")
    assert result.exit_code == 0, result.output
    assert "carbody bounce" in result.stdout and "damping ratio" in result.stdout


def test_modes_params_file(tmp_path):
    stiff = tmp_path / "stiff.toml"
    stiff.write_text('[vehicle]\npreset = "paper"\nk_sz = 5.8e5\n', encoding="utf-8")
    base = json.loads(run("modes", "--format", "json").stdout)["modes"]
    doc = json.loads(run("modes", "--format", "json", "--params", stiff, "--load", 1.2).stdout)
    assert (doc["vehicle"]["name"], doc["vehicle"]["load"]) == (str(stiff), 1.2)
    assert doc["vehicle"]["values"]["k_sz"] == 5.8e5 and doc["vehicle"]["values"]["m_c"] == 3.96e4  # before the load
    other = doc["modes"]

    def bounce(ms):
        return next(m["frequency_hz"] for m in ms if m["label"] == "carbody bounce")

    assert bounce(other) > bounce(base) * 1.2


def test_modes_bad_inputs(tmp_path):
    assert_input_error(run("modes", "--preset", "nope"), "nope")
    assert_input_error(run("modes", "--params", tmp_path / "missing.toml"), "missing.toml")
    assert run("modes", "--format", "yaml").exit_code == 2


# -- simulate: good runs --------------------------------------------------------------------------
def test_simulate_json_document():
    result = run("simulate", "--format", "json", "--duration", 2)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert list(doc) == [
        "schema",
        "railride_version",
        "versions",
        "scenario",
        "vehicle",
        "vehicle_preset",
        "suspension",
        "settings",
        "metrics",
        "travel",
    ]
    assert doc["schema"] == "railride.simulation/1"
    assert doc["travel"]["clearance_m"] == 0.08 and not doc["travel"]["reached_stops"]
    assert doc["vehicle_preset"] == "paper"
    assert {k: v for k, v in doc["vehicle"].items() if k != "values"} == {"name": "paper", "load": 1.0}
    assert doc["scenario"]["name"] == "paper-sine" and doc["scenario"]["duration_s"] == 2.0
    assert doc["scenario"]["speed_m_s"] == 55.56  # scenario default applied
    assert doc["settings"] == {"dt_s": 1e-4, "output_rate_hz": 1000.0, "window_s": [0.0, 2.0]}
    assert set(doc["metrics"]) == METRIC_KEYS
    for values in doc["metrics"].values():
        assert set(values) == {"rms", "ptp"}
        assert values["rms"] > 0 and values["ptp"] > 0


def test_simulate_window_and_overrides():
    result = run(
        "simulate",
        "--format",
        "json",
        "--duration",
        2,
        "--window",
        "1:2",
        "--amplitude",
        0.02,
        "--wavelength",
        40,
        "--rail-phase",
        0,
        "--speed",
        40,
    )
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["settings"]["window_s"] == [1.0, 2.0]
    assert doc["scenario"]["amplitude_m"] == 0.02 and doc["scenario"]["wavelength_m"] == 40.0
    assert doc["scenario"]["speed_m_s"] == 40.0
    # in-phase rails: no roll input
    assert doc["metrics"]["roll_deg"]["rms"] < 1e-9
    open_end = json.loads(run("simulate", "--format", "json", "--duration", 2, "--window", "1:").stdout)
    assert open_end["settings"]["window_s"] == [1.0, 2.0]


def test_simulate_table():
    result = run("simulate", "--duration", 1, "--scenario", "bump")
    assert result.exit_code == 0, result.output
    for text in ("RMS", "peak-to-peak", "acceleration", "displacement", "pitch", "roll", "bump"):
        assert text in result.stdout


def test_simulate_measured_file_and_params_file(good_track, tmp_path):
    params = tmp_path / "p.toml"
    params.write_text('[vehicle]\npreset = "paper"\nc_sz = 6e4\n', encoding="utf-8")
    result = run(
        "simulate", "--format", "json", "--duration", 1, "--scenario", f"file:{good_track}", "--params", params
    )
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)
    assert doc["scenario"]["profile"] == "measured"
    assert doc["vehicle_params_file"] == str(params) and "vehicle_preset" not in doc


# -- simulate: bad input, status 2 ----------------------------------------------------------------
def test_unknown_scenario():
    assert_input_error(run("simulate", "--scenario", "zigzag"), "unknown scenario")


def test_missing_track_file(tmp_path):
    assert_input_error(run("simulate", "--scenario", f"file:{tmp_path / 'nope.csv'}"), "nope.csv")


def test_track_non_numeric_cell(tmp_path):
    path = write_track(tmp_path / "bad.csv", ["s,z_L,z_R", "0,0,0", "100,abc,0", "200,0,0"])
    assert_input_error(run("simulate", "--duration", 1, "--scenario", f"file:{path}"), "abc")


def test_track_missing_column(tmp_path):
    path = write_track(tmp_path / "bad.csv", ["s,z_L", "0,0", "200,0"])
    assert_input_error(run("simulate", "--duration", 1, "--scenario", f"file:{path}"), "z_R")


@pytest.mark.parametrize("value", ["-3", "nan", "0", "inf"])
def test_bad_speed(value):
    assert_input_error(run("simulate", "--duration", 1, "--speed", value), "speed")


def test_dt_too_large():
    assert_input_error(run("simulate", "--duration", 2, "--dt", 0.05), "too large")
    # RK4 (the MR dampers) is unstable at that step; the passive vehicle's exact steps are not
    mr = ("--suspension", "mr")
    assert_input_error(run("simulate", "--duration", 2, "--dt", 0.05, "--output-rate", 20, *mr), "too large")
    ok("simulate", "--duration", 2, "--dt", 0.05, "--output-rate", 20)
    # a stable step that does not fit the output rate is bad input too
    assert_input_error(run("simulate", "--duration", 2, "--dt", 0.002), "--output-rate")


def test_library_errors_name_the_options():
    # the library checks the settings; the command line names its options in the message
    assert_input_error(
        run("simulate", "--duration", 2, "--dt", 0.002),
        "error: --dt = 0.002 s is too large for --output-rate = 1000 Hz (the default): at "
        "most one output sample per step; use --dt <= 0.001 s or a lower --output-rate",
    )
    from railride.cli._common import reworded

    fields = {"dt": "--dt", "output_rate": "--output-rate", "'seed'": "--seed"}
    # a plain name where it names a value, a name with an underscore wherever it stands (not in
    # a formula), a field quoted as the parameter checks quote it
    assert reworded("the dt of a run; dt = 1 s, dt <= 2 s", fields) == "the dt of a run; --dt = 1 s, --dt <= 2 s"
    assert reworded("raise output_rate; 1/output_rate", fields) == "raise --output-rate; 1/output_rate"
    assert reworded("sensor noise 'seed' = -1: must be", fields) == "sensor noise --seed = -1: must be"
    assert (
        reworded("output_rate = 300 Hz with dt = 0.0001 s: whole", fields, ["dt"])
        == "--output-rate = 300 Hz with --dt = 0.0001 s (the default): whole"
    )


def test_the_document_is_the_library_one():
    from railride.run.simulation import simulate
    from railride.secondary.suspension import Suspension
    from railride.model.track import scenario

    doc = json.loads(
        run(
            "simulate", "--suspension", "mr", "--voltage", 1, "--damper-scale", 2, "--duration", 1, "--format", "json"
        ).stdout
    )
    from railride.model.params import VehicleParams, vehicle_record

    library = simulate(
        scenario("paper-sine", duration=1.0), "paper", Suspension.named("mr", damper_scale=2.0, voltage=1.0)
    ).to_dict()
    # the command's document is the library's: the vehicle by the record every output keeps
    record = vehicle_record(VehicleParams.preset("paper"), "paper")
    assert doc["vehicle"] == library["vehicle"] == record
    assert doc == library and list(doc) == list(library)
    assert doc["suspension"]["damper_scale"] == 2.0


def test_window_outside_run():
    assert_input_error(run("simulate", "--duration", 2, "--window", "5:20"), "window")


@pytest.mark.parametrize("rate", ["nan", "-1000", "0"])
def test_bad_output_rate_with_window(rate):
    assert_input_error(run("simulate", "--duration", 1, "--window", "0:1", "--output-rate", rate), "--output-rate")


@pytest.mark.parametrize("window", ["abc", "1:2:3", "2:1"])
def test_malformed_window(window):
    assert_input_error(run("simulate", "--duration", 2, "--window", window), "window")


def test_negative_mass_params(tmp_path):
    path = tmp_path / "neg.toml"
    path.write_text('[vehicle]\npreset = "paper"\nm_c = -1.0\n', encoding="utf-8")
    assert_input_error(run("simulate", "--duration", 1, "--params", path), "m_c")


def test_malformed_toml(tmp_path):
    path = tmp_path / "broken.toml"
    path.write_text("[vehicle\nm_c = \n", encoding="utf-8")
    assert_input_error(run("simulate", "--duration", 1, "--params", path), "TOML")


def test_params_and_preset_exclusive(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text('[vehicle]\npreset = "paper"\n', encoding="utf-8")
    assert_input_error(run("simulate", "--params", path, "--preset", "paper"), "not both")


def test_option_not_for_scenario():
    assert_input_error(run("simulate", "--scenario", "bump", "--rail-phase", 30), "--rail-phase")


def test_unknown_format():
    result = run("simulate", "--format", "xml")
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    assert result.stdout == ""


def test_not_a_number_is_usage_error():
    result = run("simulate", "--speed", "fast")
    assert result.exit_code == 2 and "Traceback" not in result.output


def test_diverged_run_status_2(monkeypatch):
    import importlib

    from railride.errors import DivergenceError

    # the module, not the function of the same name that railride/__init__.py re-exports
    core = importlib.import_module("railride.run.simulation")

    def boom(*args, **kwargs):
        raise DivergenceError("the simulation diverged (sample 0 at t = 1 s)")

    monkeypatch.setattr(core, "simulate", boom)
    result = run("simulate", "--duration", 1)
    assert result.exit_code == 2  # its inputs diverged: the user's to change
    assert result.stderr.strip() == "error: the simulation diverged (sample 0 at t = 1 s)"
    assert "Traceback" not in result.output


# -- --out ----------------------------------------------------------------------------------------
def test_out_writes_four_files(tmp_path):
    out = tmp_path / "run1"
    result = run("simulate", "--format", "json", "--duration", 1, "--out", out)
    assert result.exit_code == 0, result.output
    doc = json.loads(result.stdout)  # stdout stays clean JSON
    assert sorted(p.name for p in out.iterdir()) == ["body_responses.png", "metrics.json", "ride.csv", "ride.nc"]
    assert json.loads((out / "metrics.json").read_text()) == doc
    with xr.open_dataset(out / "ride.nc", engine="scipy") as ds:
        assert "carbody_bounce" in ds and ds.sizes["time"] == 1001
        assert json.loads(str(ds["scenario"].values))["duration_s"] == 1.0
        assert json.loads(str(ds["vehicle_params"].values))["m_c"] == 39600.0
        assert list(ds["corner"].values) == ["1R", "1L", "2R", "2L"]
    header = (out / "ride.csv").read_text().splitlines()[0].split(",")
    assert header[0] == "time" and "secondary_deflection_1R" in header and "rail_displacement_4R" in header
    assert (out / "body_responses.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["run1"]  # no staging left behind


def test_failing_run_leaves_out_absent(tmp_path):
    out = tmp_path / "absent"
    assert_input_error(run("simulate", "--duration", 2, "--window", "5:20", "--out", out))
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


def test_failing_run_leaves_out_unchanged(tmp_path):
    out = tmp_path / "existing"
    assert run("simulate", "--duration", 1, "--out", out).exit_code == 0
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert_input_error(run("simulate", "--duration", 2, "--window", "5:20", "--out", out))
    assert_input_error(run("simulate", "--duration", 1, "--speed", "nan", "--out", out))
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["existing"]


def test_out_is_a_file(tmp_path):
    target = tmp_path / "file.txt"
    target.write_text("keep me")
    assert_input_error(run("simulate", "--duration", 1, "--out", target), "not a folder")
    assert target.read_text() == "keep me"


# -- the console script -----------------------------------------------------------------------------
def test_module_entry_point_error_path():
    proc = subprocess.run(
        [sys.executable, "-m", "railride.cli", "simulate", "--speed", "-3"], capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 2
    assert proc.stderr.strip().splitlines() == ["error: --speed = -3.0: must be a finite number > 0 (m/s)"]
    assert proc.stdout == ""


def test_no_args_shows_help():
    result = run()
    assert "modes" in result.output and "simulate" in result.output


def test_version_and_python_dash_m():
    import subprocess
    import sys

    from railride import __version__

    assert ok("--version").stdout.strip() == f"railride {__version__}"
    out = subprocess.run([sys.executable, "-m", "railride", "--version"], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == f"railride {__version__}"
