"""The result folders of railride.output.files: NetCDF, and the all-or-nothing output folder."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from railride import _io
from railride.output import files
from railride.run.simulation import simulate
from railride.model.track import scenario

DOC = {"schema": "test", "metrics": {"a": {"rms": 1.0, "ptp": 2.0}}}


@pytest.fixture(scope="module")
def result():
    return simulate(scenario("paper-sine", duration=1.0))


@pytest.fixture(scope="module")
def batch():
    return simulate([scenario("paper-sine", duration=0.5), scenario("bump", duration=0.5)])


# -- NetCDF ---------------------------------------------------------------------------------------
def test_netcdf_keeps_integer_coordinates_and_text(tmp_path):
    ds = xr.Dataset(
        {"label": ((), json.dumps({"source": "trück ψ.csv"}))},
        coords={"x": np.array([10, 20], dtype=np.int64)},
        attrs={"ok": "ψ = 90°"},
    )
    path = tmp_path / "odd.nc"
    files.write_netcdf(ds, path)
    with xr.open_dataset(path, engine="scipy") as back:
        assert back["x"].values.tolist() == [10, 20]
        assert json.loads(str(back["label"].values))["source"] == "trück ψ.csv"
        assert back.attrs["ok"] == "ψ = 90°"
    with pytest.raises(ValueError, match="beyond int32"):
        files.write_netcdf(xr.Dataset({"big": ("x", np.array([2**40]))}), tmp_path / "big.nc")


def test_result_netcdf_round_trip(result, tmp_path):
    path = tmp_path / "ride.nc"
    files.write_netcdf(result.dataset, path)
    with xr.open_dataset(path, engine="scipy") as back:
        xr.testing.assert_allclose(back["carbody_bounce"], result.dataset["carbody_bounce"])
        assert str(back["scenario"].values) == str(result.dataset["scenario"].values)
        assert str(back["vehicle_params"].values) == str(result.dataset["vehicle_params"].values)
        assert set(back.attrs) == set(result.dataset.attrs)
        assert back["secondary_deflection"].attrs["long_name"].startswith("secondary")


# -- write_outputs ----------------------------------------------------------------------------------
def test_write_outputs_new_folder(result, tmp_path):
    out = tmp_path / "deep" / "out"
    paths = files.write_outputs(result, out, DOC)
    assert [p.name for p in paths] == list(files.OUTPUT_FILES)
    assert sorted(p.name for p in out.iterdir()) == sorted(files.OUTPUT_FILES)
    assert json.loads((out / "metrics.json").read_text()) == DOC
    csv = pd.read_csv(out / "ride.csv", index_col="time")
    assert "secondary_deflection_1R" in csv.columns and len(csv) == result.dataset.sizes["time"]
    assert [p.name for p in (tmp_path / "deep").iterdir()] == ["out"]
    mask = os.umask(0)
    os.umask(mask)
    for p in paths:  # ordinary permissions, not the 0600 of temporary files
        assert (p.stat().st_mode & 0o777) == (0o666 & ~mask)


def test_write_outputs_batch(batch, tmp_path):
    out = tmp_path / "b"
    files.write_outputs(batch, out, DOC)
    head = (out / "ride.csv").read_text().splitlines()[0].split(",")
    assert head[:2] == ["sample", "time"]
    with xr.open_dataset(out / "ride.nc", engine="scipy") as back:
        assert back.sizes["sample"] == 2 and back["scenario"].shape == (2,)


def test_write_outputs_takes_a_ride_result(result, tmp_path):
    with pytest.raises(ValueError, match="result: expected a railride.run.ride.RideResult, got Dataset"):
        files.write_outputs(result.dataset, tmp_path / "out", DOC)
    assert list(tmp_path.iterdir()) == []


def test_write_outputs_existing_folder_keeps_other_files(result, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "metrics.json").write_text("old")
    files.write_outputs(result, out, DOC)
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "metrics.json").read_text()) == DOC
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def _failing_png(*args, **kwargs):
    raise OSError("disk full (simulated)")


def test_write_outputs_failure_new_folder(result, tmp_path, monkeypatch):
    monkeypatch.setattr(files, "plot_body_responses", _failing_png)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="simulated"):
        files.write_outputs(result, out, DOC)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []  # staging removed


def test_write_outputs_failure_existing_folder(result, tmp_path, monkeypatch):
    out = tmp_path / "out"
    files.write_outputs(result, out, {"first": True})
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(files, "plot_body_responses", _failing_png)
    with pytest.raises(OSError):
        files.write_outputs(result, out, DOC)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_write_outputs_rejects_nan_metrics(result, tmp_path):
    with pytest.raises(ValueError):
        files.write_outputs(result, tmp_path / "out", {"rms": float("nan")})
    assert list(tmp_path.iterdir()) == []


def test_write_outputs_rolls_back_failed_move(result, tmp_path, monkeypatch):
    out = tmp_path / "out"
    files.write_outputs(result, out, {"first": True})
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real_replace = os.replace

    def flaky(src, dst):
        new_file = ".staging-" in str(src) and ".previous" not in str(src)
        if new_file and str(dst) == str(out / "metrics.json"):
            raise OSError("rename failed (simulated)")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(OSError, match="simulated"):
        files.write_outputs(result, out, DOC)
    monkeypatch.undo()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_check_out_dir_rejects_file(tmp_path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(ValueError, match="not a folder"):
        files.check_out_dir(f)
    with pytest.raises(ValueError, match="not a folder"):
        files.check_out_dir(f / "sub")


def _other_file_system(tmp_path):
    """A writable folder on another file system than tmp_path, or None."""
    for root in ("/dev/shm", "/run/user", "/tmp"):
        try:
            if os.path.isdir(root) and os.stat(root).st_dev != os.stat(tmp_path).st_dev:
                return root
        except OSError:
            continue
    return None


@pytest.mark.parametrize("elsewhere", ["same file system", "another file system"])
def test_out_through_a_link_writes_into_the_folder_it_leads_to(result, tmp_path, elsewhere):
    import tempfile

    if elsewhere == "same file system":
        target = tmp_path / "real"
    else:
        root = _other_file_system(tmp_path)
        if root is None:
            pytest.skip("no second file system to link to")
        target = Path(tempfile.mkdtemp(dir=root))
    try:
        target.mkdir(exist_ok=True)
        link = tmp_path / "out"
        link.symlink_to(target)
        files.write_folder(link, [("a.txt", lambda p: p.write_text("a")), ("b.txt", lambda p: p.write_text("b"))])
        # renamed on the target's file system (beside the link they would cross: EXDEV)
        assert sorted(p.name for p in target.iterdir()) == ["a.txt", "b.txt"]
        assert link.is_symlink() and not list(tmp_path.glob(".out.staging-*"))
    finally:
        if elsewhere != "same file system":
            import shutil

            shutil.rmtree(target, ignore_errors=True)


# -- the umask of atomic writes ---------------------------------------------------------------------
def _refuse_umask(mask):
    raise AssertionError("os.umask called: setting the umask to read it changes it for every thread")


@pytest.mark.skipif(_io._proc_umask() is None, reason="needs the Umask: line of /proc/self/status (Linux 4.7+)")
def test_an_atomic_write_reads_the_umask_without_setting_it(tmp_path, monkeypatch):
    previous = os.umask(0o027)
    try:
        monkeypatch.setattr(os, "umask", _refuse_umask)
        assert _io.umask() == 0o027  # the umask now, not the one at import
        _io.atomic_write_text(tmp_path / "a.txt", "a")
        assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o666 & ~0o027
    finally:
        monkeypatch.undo()
        os.umask(previous)


def test_without_proc_an_atomic_write_takes_the_umask_read_at_import(tmp_path, monkeypatch):
    monkeypatch.setattr(_io, "_proc_umask", lambda: None)
    monkeypatch.setattr(_io, "_IMPORT_UMASK", 0o077)
    monkeypatch.setattr(os, "umask", _refuse_umask)
    _io.atomic_write_text(tmp_path / "a.txt", "a")
    assert (tmp_path / "a.txt").stat().st_mode & 0o777 == 0o600
