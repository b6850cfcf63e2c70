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
