"""`railride.frequency.ride_spectrum.RideSpectrum`: what its arrays carry (CF attributes, the
device of each suspension) and its reductions against passive, signed as `railride compare`'s."""

from __future__ import annotations

import math

import pytest

from railride.frequency.ride_spectrum import ACTUATOR_DEVICE, PASSIVE_DEVICE, RESPONSES, ride_spectrum


@pytest.fixture(scope="module")
def result():
    return ride_spectrum("fra4", controllers=("passive", "pid"), points=32)


def test_every_array_and_coordinate_has_a_long_name_and_units(result):
    arrays = {**{f"psd.{k}": v for k, v in result.psd.variables.items()}}
    for name, da in (("rms", result.rms), ("weighted", result.weighted)):
        arrays[name] = da
        arrays.update({f"{name}.{k}": v for k, v in da.coords.items()})
    assert {"psd.frequency", "psd.suspension", "psd.device", "rms.response", "weighted.weighting"} <= set(arrays)
    for name, da in arrays.items():
        assert isinstance(da.attrs.get("long_name"), str) and da.attrs["long_name"], name
        assert isinstance(da.attrs.get("units"), str), name  # "" for a label
    assert result.psd["frequency"].attrs["units"] == "Hz"
    assert result.psd["floor_acceleration_centre"].attrs["units"] == "(m/s^2)^2/Hz"
    assert result.weighted.attrs["units"] == "m/s^2"
    assert result.psd["suspension"].attrs["units"] == ""  # a label: no unit (CF: "1" is for dimensionless numbers)
    # the RMS spans responses of different units: each its own
    units = dict(zip(result.rms["response"].values, result.rms["unit"].values))
    assert units["carbody_pitch_acceleration"] == "rad/s^2" and units["secondary_deflection_1R"] == "m"


def test_each_suspension_names_its_device(result):
    assert result.devices == {"passive": PASSIVE_DEVICE, "pid": ACTUATOR_DEVICE}
    assert result.to_dict()["devices"] == result.devices
    frame = result.to_pandas()
    assert set(frame.loc[frame["suspension"] == "pid", "device"]) == {"ideal actuator"}


def test_reductions_are_positive_where_the_controller_is_better(result):
    """(passive - controlled) / passive x 100 from the document's own RMS values: PID on the
    ideal actuator lowers the floor acceleration (positive) and lengthens the secondary travel
    (negative), as compare's red. % would say."""
    doc = result.to_dict()
    for r in RESPONSES:
        p, c = doc["rms"]["passive"][r], doc["rms"]["pid"][r]
        assert math.isclose(doc["rms_reduction_percent"]["pid"][r], 100 * (1 - c / p), rel_tol=1e-12)
    assert doc["rms"]["pid"]["floor_acceleration_centre"] < doc["rms"]["passive"]["floor_acceleration_centre"]
    assert doc["rms_reduction_percent"]["pid"]["floor_acceleration_centre"] > 0
    assert doc["rms"]["pid"]["secondary_deflection_1R"] > doc["rms"]["passive"]["secondary_deflection_1R"]
    assert doc["rms_reduction_percent"]["pid"]["secondary_deflection_1R"] < 0
    wb = doc["weighted_rms_m_s2"]
    assert math.isclose(
        doc["weighted_rms_reduction_percent"]["pid"]["front"]["Wb"],
        100 * (wb["passive"]["front"]["Wb"] - wb["pid"]["front"]["Wb"]) / wb["passive"]["front"]["Wb"],
        rel_tol=1e-12,
    )
    assert "passive" not in doc["rms_reduction_percent"]
    row = result.to_pandas().set_index(["suspension", "response"]).loc[("pid", "floor_acceleration_rear")]
    assert math.isclose(row["aw_Wk_reduction_percent"], doc["weighted_rms_reduction_percent"]["pid"]["rear"]["Wk"])


def test_no_reductions_without_passive():
    doc = ride_spectrum("fra4", controllers=("pid",), points=16).to_dict()
    assert doc["rms_reduction_percent"] == {} and doc["weighted_rms_reduction_percent"] == {}
    assert doc["devices"] == {"pid": "ideal actuator"}
