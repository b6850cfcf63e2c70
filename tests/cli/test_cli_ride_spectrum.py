"""``railride ride-spectrum`` and ``railride state-space``: tables, documents, files and
input errors."""

from __future__ import annotations

import json

from scipy.io import loadmat

from clihelp import assert_input_error, ok, ok_json, run


def test_ride_spectrum_table_and_json():
    out = ok("ride-spectrum", "--controllers", "passive,sas-attitude", "--points", "200").stdout
    assert "Carbody floor acceleration (m/s^2)" in out and "SAS (attitude)" in out
    assert "(the shipped robust set, tuned on FRA classes 4 and 5" in " ".join(out.split())
    doc = ok_json("ride-spectrum", "--track", "fra5", "--speed", "40", "--points", "200")
    assert doc["settings"]["track"] == "fra5" and doc["settings"]["speed_m_s"] == 40.0
    assert set(doc["rms"]) == {"passive", "pid", "sas-attitude", "sas-attitude-ride"}


def test_ride_spectrum_says_which_device_and_signs_reductions_as_compare():
    """The first line names the ideal actuator; red. % is (passive - controlled) / passive x 100,
    positive where the controller is better, worked out here from the document's RMS values."""
    args = ("ride-spectrum", "--controllers", "passive,pid", "--points", "64")
    out = ok(*args).stdout
    assert "ideal actuator" in out.splitlines()[0].lower()
    assert "MR dampers" in " ".join(out.split()) and "red. % = (passive - controlled) / passive x 100" in out
    doc = ok_json(*args)
    rms = {s: doc["rms"][s]["floor_acceleration_centre"] for s in ("passive", "pid")}
    wb = {s: doc["weighted_rms_m_s2"][s]["centre"]["Wb"] for s in ("passive", "pid")}
    (row,) = [line for line in out.splitlines() if line.startswith("│ PID") and "centre" in line]
    cells = [c.strip() for c in row.strip("│").split("│")]
    assert cells[:2] == ["PID", "centre"]
    assert cells[3] == f"{100 * (rms['passive'] - rms['pid']) / rms['passive']:.1f}" and float(cells[3]) > 0
    assert cells[5] == f"{100 * (wb['passive'] - wb['pid']) / wb['passive']:.1f}" and float(cells[5]) > 0
    assert doc["devices"] == {"passive": "passive viscous dampers", "pid": "ideal actuator"}
    # passive alone: no controller, no device to warn of, no reductions
    alone = ok("ride-spectrum", "--controllers", "passive", "--points", "32").stdout
    assert "ideal actuator" not in alone.splitlines()[0] and "red. % =" not in alone


def test_ride_spectrum_warns_of_gains_tuned_for_another_case(tmp_path):
    """Gains tuned for another vehicle, load or track: one ``warning:`` line on stderr before the
    results, recorded as ``settings.gains_mismatch`` (as compare says it). Gains tuned on any
    realisation of this spectrum, speed and band are tuned on it: nothing; nor for passive alone."""
    from railride.model.track import scenario
    from railride.secondary.control import GainSet

    record = scenario("fra4", seed=3, duration=30.0).describe()
    inline = ", ".join(f"{k} = {json.dumps(v)}" for k, v in record.items())
    gains = tmp_path / "fra4.toml"
    gains.write_text(f"[provenance]\nscenario_record = {{{inline}}}\n\n{GainSet.reference().to_toml()}")
    args = ("ride-spectrum", "--points", 32, "--controllers", "passive,pid", "--gains", gains)
    here = ok(*args, "--format", "json")
    assert here.stderr == "" and "gains_mismatch" not in json.loads(here.stdout)["settings"]
    table = " ".join(ok(*args).stdout.split())  # the note, wherever it wraps
    assert "fra4.toml" in "".join(table.split()) and "(the shipped robust set" not in table  # a long path wraps
    faster = ok(*args, "--speed", 40, "--load", 1.2, "--format", "json")
    (line,) = faster.stderr.splitlines()
    assert line.startswith(f"warning: the gains {gains} were tuned for vehicle paper, load 1")
    assert "this run has load 1.2, track fra4 (speed 40 m/s); tune for it with: railride tune --load 1.2" in line
    assert json.loads(faster.stdout)["settings"]["gains_mismatch"] == line.removeprefix("warning: ")
    # the paper set, tuned on the paper's sine track; passive reads no gains
    paper = ok("ride-spectrum", "--points", 32, "--controllers", "pid", "--gains", "paper").stderr
    assert paper.startswith("warning: the gains railride/data/gains.toml were tuned for vehicle paper, load 1, on ")
    assert "this run has track fra4" in paper and paper.count("\n") == 1
    # without --gains, the robust set, whose range covers fra4 at 55.56 m/s: nothing to say
    robust = ok("ride-spectrum", "--points", 32, "--controllers", "pid")
    assert robust.stderr == "" and "(the shipped robust set" in " ".join(robust.stdout.split())
    assert ok("ride-spectrum", "--points", 32, "--controllers", "passive", "--gains", gains, "--speed", 40).stderr == ""


def test_ride_spectrum_lists_unstable_loops_and_writes_files(tmp_path):
    out = ok("ride-spectrum", "--controllers", "passive,groundhook", "--points", "100", "--out", tmp_path / "rs").stdout
    assert "not run: groundhook" in out
    assert (tmp_path / "rs" / "ride_spectrum_psd.csv").is_file()


def test_ride_spectrum_input_errors():
    assert_input_error(run("ride-spectrum", "--track", "sine"), "--track = 'sine'")
    assert_input_error(run("ride-spectrum", "--controllers", "mr"), "--controllers = 'mr'")
    assert_input_error(run("ride-spectrum", "--points", "2"), "--points = 2")
    assert_input_error(run("ride-spectrum", "--control-rate", "-5"), "--control-rate")


def test_state_space_writes_mat_and_json(tmp_path):
    ok("state-space", "--suspension", "pid", "--out", tmp_path / "pid.mat")
    data = loadmat(tmp_path / "pid.mat")
    assert data["A"].shape == (21, 21) and data["B"].shape == (21, 16)
    doc = ok_json("state-space", "--suspension", "plant")
    assert doc["inputs"][-1] == "secondary_force_2L" and len(doc["A"]) == 18
    assert_input_error(run("state-space", "--out", tmp_path / "m.txt"), "--out", ".mat or .json")
    assert_input_error(run("state-space", "--suspension", "mr"), "--suspension = 'mr'", "not a linear suspension")
    assert_input_error(run("state-space", "--suspension", "pid,skyhook"), "one suspension at a time")


def test_time_histories_as_matlab_files(tmp_path):
    """--history-format mat writes ride.mat (and compare.mat) holding the histories of the
    NetCDF file; a bad format, or one without --out, exits 2."""
    import numpy as np
    import xarray as xr

    ok("simulate", "--duration", 1, "--out", tmp_path / "s", "--history-format", "mat,nc")
    names = sorted(p.name for p in (tmp_path / "s").iterdir())
    assert "ride.mat" in names and "ride.nc" in names and "ride.csv" not in names
    data = loadmat(tmp_path / "s" / "ride.mat", simplify_cells=True)
    with xr.open_dataset(tmp_path / "s" / "ride.nc", engine="scipy") as ds:
        assert np.array_equal(data["carbody_bounce"], ds["carbody_bounce"].values)
        assert np.array_equal(data["secondary_damper_force"], ds["secondary_damper_force"].transpose("time", "corner"))
    assert data["units"]["carbody_pitch"] == "rad" and list(data["dims"]["rail_displacement"]) == [
        "time",
        "wheelset",
        "rail",
    ]
    ok("compare", "--duration", 1, "--controllers", "sas-attitude", "--out", tmp_path / "c", "--history-format", "mat")
    data = loadmat(tmp_path / "c" / "compare.mat", simplify_cells=True)
    assert list(data["controller"]) == ["passive", "sas-attitude"] and data["carbody_acceleration"].shape == (1001, 2)
    assert_input_error(
        run("simulate", "--duration", 1, "--out", tmp_path / "x", "--history-format", "hdf5"),
        "--history-format = 'hdf5'",
    )
    assert_input_error(run("simulate", "--duration", 1, "--history-format", "mat"), "--history-format", "--out")


def test_the_travel_a_law_adds_is_said_beside_the_floor():
    """Each law whose RMS travel (1R) is above passive's by more than 1 % is named with the rise
    read off the JSON document's own RMS values."""
    doc = ok_json("ride-spectrum", "--format", "json")
    base = doc["rms"]["passive"]["secondary_deflection_1R"]
    text = " ".join(ok("ride-spectrum").stdout.split())
    for name, label in (("pid", "PID"), ("sas-attitude", "SAS (attitude)")):
        rise = 100 * (doc["rms"][name]["secondary_deflection_1R"] / base - 1)
        assert rise > 1 and f"{label} {rise:+.3g} %" in text
