"""The flat tables of railride.output.tables."""

from __future__ import annotations

import numpy as np
import pytest

from railride.output import tables
from railride.run.simulation import simulate
from railride.model.track import scenario


@pytest.fixture(scope="module")
def result():
    return simulate(scenario("paper-sine", duration=1.0))


@pytest.fixture(scope="module")
def batch():
    return simulate([scenario("paper-sine", duration=0.5), scenario("bump", duration=0.5)])


def test_to_frame_single(result):
    ds = result.dataset
    df = tables.to_frame(ds)
    assert df.index.name == "time" and len(df) == ds.sizes["time"]
    assert "secondary_deflection_1R" in df.columns
    assert "rail_displacement_1L" in df.columns and "rail_velocity_4R" in df.columns
    assert "carbody_bounce" in df.columns and "carbody_acceleration" in df.columns
    assert "scenario" not in df.columns and "vehicle_params" not in df.columns
    assert not any(c.startswith(("scenario", "vehicle_params")) for c in df.columns)
    np.testing.assert_array_equal(
        df["secondary_deflection_2L"].values, ds["secondary_deflection"].sel(corner="2L").values
    )
    np.testing.assert_array_equal(
        df["rail_displacement_3R"].values, ds["rail_displacement"].sel(wheelset=3, rail="R").values
    )
    np.testing.assert_array_equal(df.index.values, ds["time"].values)
    # 18 DOF channels + 3 carbody accelerations + 5 corner channels x 4 + 2 rail channels x 8
    assert df.shape[1] == 18 + 3 + 5 * 4 + 2 * 8
    assert result.to_pandas().equals(df)


def test_to_frame_batch(batch):
    ds = batch.dataset
    df = tables.to_frame(ds)
    assert df.index.names == ["sample", "time"]
    assert len(df) == ds.sizes["sample"] * ds.sizes["time"]
    np.testing.assert_array_equal(
        df.loc[1]["secondary_deflection_1R"].values, ds["secondary_deflection"].sel(sample=1, corner="1R").values
    )
    flat = df.reset_index()
    assert list(flat.columns[:2]) == ["sample", "time"]


def test_to_frame_takes_the_dataset_not_the_result(result):
    with pytest.raises(ValueError, match="ds: expected an xarray Dataset"):
        tables.to_frame(result)


def test_modes_frame_numbers_the_mode_records():
    records = [
        {"label": "bounce", "frequency_hz": 1.0, "damped_frequency_hz": 0.99, "damping_ratio": 0.1},
        {"label": "pitch", "frequency_hz": 1.5, "damped_frequency_hz": 1.4, "damping_ratio": 0.2},
    ]
    frame = tables.modes_frame(records)
    assert list(frame.columns) == list(tables.MODE_COLUMNS)
    assert frame["mode"].tolist() == [1, 2] and frame["label"].tolist() == ["bounce", "pitch"]
