"""``railride ride-spectrum`` and ``railride state-space``: tables, documents, files and
input errors."""

from __future__ import annotations

from scipy.io import loadmat

from clihelp import assert_input_error, ok, ok_json, run


def test_ride_spectrum_table_and_json():
    out = ok("ride-spectrum", "--controllers", "passive,sas-attitude", "--points", "200").stdout
    assert "Carbody floor acceleration [m/s^2]" in out and "SAS (attitude)" in out
    assert "tuned on the paper's sine track" in out
    doc = ok_json("ride-spectrum", "--track", "fra5", "--speed", "40", "--points", "200")
    assert doc["settings"]["track"] == "fra5" and doc["settings"]["speed_m_s"] == 40.0
    assert set(doc["rms"]) == {"passive", "pid", "sas-attitude", "sas-attitude-ride"}


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
    assert_input_error(run("state-space", "--suspension", "mr"), "--suspension = 'mr'")
