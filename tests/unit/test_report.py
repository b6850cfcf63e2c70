"""The report layer: flat tables, the body-response plot and the all-or-nothing output folder."""

from __future__ import annotations

import json
import os

import numpy as np
import pandas as pd
import pytest
import xarray as xr

from railride import report
from railride.simulation import simulate
from railride.track import scenario

DOC = {"schema": "test", "metrics": {"a": {"rms": 1.0, "ptp": 2.0}}}


@pytest.fixture(scope="module")
def result():
    return simulate(scenario("paper-sine", duration=1.0))


@pytest.fixture(scope="module")
def batch():
    return simulate([scenario("paper-sine", duration=0.5), scenario("bump", duration=0.5)])


# -- to_frame -------------------------------------------------------------------------------------
def test_to_frame_single(result):
    ds = result.dataset
    df = report.to_frame(ds)
    assert df.index.name == "time" and len(df) == ds.sizes["time"]
    assert "secondary_deflection_1R" in df.columns
    assert "rail_displacement_1L" in df.columns and "rail_velocity_4R" in df.columns
    assert "carbody_bounce" in df.columns and "carbody_acceleration" in df.columns
    assert "scenario" not in df.columns and "vehicle_params" not in df.columns
    assert not any(c.startswith(("scenario", "vehicle_params")) for c in df.columns)
    np.testing.assert_array_equal(df["secondary_deflection_2L"].values,
                                  ds["secondary_deflection"].sel(corner="2L").values)
    np.testing.assert_array_equal(df["rail_displacement_3R"].values,
                                  ds["rail_displacement"].sel(wheelset=3, rail="R").values)
    np.testing.assert_array_equal(df.index.values, ds["time"].values)
    # 18 DOF channels + 3 carbody accelerations + 5 corner channels x 4 + 2 rail channels x 8
    assert df.shape[1] == 18 + 3 + 5 * 4 + 2 * 8
    assert result.to_pandas().equals(df)


def test_to_frame_batch(batch):
    ds = batch.dataset
    df = report.to_frame(ds)
    assert df.index.names == ["sample", "time"]
    assert len(df) == ds.sizes["sample"] * ds.sizes["time"]
    np.testing.assert_array_equal(df.loc[1]["secondary_deflection_1R"].values,
                                  ds["secondary_deflection"].sel(sample=1, corner="1R").values)
    flat = df.reset_index()
    assert list(flat.columns[:2]) == ["sample", "time"]


# -- plot -----------------------------------------------------------------------------------------
def test_plot_body_responses(result, tmp_path):
    import matplotlib.pyplot as plt

    path = tmp_path / "fig.png"
    fig = report.plot_body_responses(result.dataset, path)
    axes = fig.get_axes()
    assert len(axes) == 4
    labels = [ax.get_ylabel() for ax in axes]
    assert "m/s" in labels[0] and "(m)" in labels[1] and "deg" in labels[2] and "deg" in labels[3]
    assert axes[-1].get_xlabel() == "time (s)"
    assert "paper-sine" in fig._suptitle.get_text()
    # pitch is plotted in degrees
    y = axes[2].lines[0].get_ydata()
    np.testing.assert_allclose(y, np.rad2deg(result.dataset["carbody_pitch"].values))
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert [p.name for p in tmp_path.iterdir()] == ["fig.png"]
    assert plt.get_fignums() == []  # nothing registered with pyplot


def test_plot_batch_one_line_per_sample(batch):
    fig = report.plot_body_responses(batch.dataset)
    for ax in fig.get_axes():
        assert len(ax.lines) == 2


# -- NetCDF ---------------------------------------------------------------------------------------
def test_netcdf_keeps_integer_coordinates_and_text(tmp_path):
    ds = xr.Dataset({"label": ((), json.dumps({"source": "trück ψ.csv"}))},
                    coords={"x": np.array([10, 20], dtype=np.int64)}, attrs={"ok": "ψ = 90°"})
    path = tmp_path / "odd.nc"
    report.write_netcdf(ds, path)
    with xr.open_dataset(path, engine="scipy") as back:
        assert back["x"].values.tolist() == [10, 20]
        assert json.loads(str(back["label"].values))["source"] == "trück ψ.csv"
        assert back.attrs["ok"] == "ψ = 90°"
    with pytest.raises(ValueError, match="beyond int32"):
        report.write_netcdf(xr.Dataset({"big": ("x", np.array([2**40]))}), tmp_path / "big.nc")


def test_result_netcdf_round_trip(result, tmp_path):
    path = tmp_path / "ride.nc"
    report.write_netcdf(result.dataset, path)
    with xr.open_dataset(path, engine="scipy") as back:
        xr.testing.assert_allclose(back["carbody_bounce"], result.dataset["carbody_bounce"])
        assert str(back["scenario"].values) == str(result.dataset["scenario"].values)
        assert str(back["vehicle_params"].values) == str(result.dataset["vehicle_params"].values)
        assert set(back.attrs) == set(result.dataset.attrs)
        assert back["secondary_deflection"].attrs["long_name"].startswith("secondary")


# -- write_outputs ----------------------------------------------------------------------------------
def test_write_outputs_new_folder(result, tmp_path):
    out = tmp_path / "deep" / "out"
    paths = report.write_outputs(result, out, DOC)
    assert [p.name for p in paths] == list(report.OUTPUT_FILES)
    assert sorted(p.name for p in out.iterdir()) == sorted(report.OUTPUT_FILES)
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
    report.write_outputs(batch, out, DOC)
    head = (out / "ride.csv").read_text().splitlines()[0].split(",")
    assert head[:2] == ["sample", "time"]
    with xr.open_dataset(out / "ride.nc", engine="scipy") as back:
        assert back.sizes["sample"] == 2 and back["scenario"].shape == (2,)


def test_write_outputs_existing_folder_keeps_other_files(result, tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine")
    (out / "metrics.json").write_text("old")
    report.write_outputs(result, out, DOC)
    assert (out / "notes.txt").read_text() == "mine"
    assert json.loads((out / "metrics.json").read_text()) == DOC
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def _failing_png(*args, **kwargs):
    raise OSError("disk full (simulated)")


def test_write_outputs_failure_new_folder(result, tmp_path, monkeypatch):
    monkeypatch.setattr(report, "plot_body_responses", _failing_png)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="simulated"):
        report.write_outputs(result, out, DOC)
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []  # staging removed


def test_write_outputs_failure_existing_folder(result, tmp_path, monkeypatch):
    out = tmp_path / "out"
    report.write_outputs(result, out, {"first": True})
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    monkeypatch.setattr(report, "plot_body_responses", _failing_png)
    with pytest.raises(OSError):
        report.write_outputs(result, out, DOC)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_write_outputs_rejects_nan_metrics(result, tmp_path):
    with pytest.raises(ValueError):
        report.write_outputs(result, tmp_path / "out", {"rms": float("nan")})
    assert list(tmp_path.iterdir()) == []


def test_write_outputs_rolls_back_failed_move(result, tmp_path, monkeypatch):
    out = tmp_path / "out"
    report.write_outputs(result, out, {"first": True})
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    real_replace = os.replace

    def flaky(src, dst):
        new_file = ".staging-" in str(src) and ".previous" not in str(src)
        if new_file and str(dst) == str(out / "metrics.json"):
            raise OSError("rename failed (simulated)")
        return real_replace(src, dst)

    monkeypatch.setattr(os, "replace", flaky)
    with pytest.raises(OSError, match="simulated"):
        report.write_outputs(result, out, DOC)
    monkeypatch.undo()
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert [p.name for p in tmp_path.iterdir()] == ["out"]


def test_check_out_dir_rejects_file(tmp_path):
    f = tmp_path / "f"
    f.write_text("x")
    with pytest.raises(ValueError, match="not a folder"):
        report.check_out_dir(f)
    with pytest.raises(ValueError, match="not a folder"):
        report.check_out_dir(f / "sub")
