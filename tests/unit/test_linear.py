"""The state-space export: MATLAB files and python-control read back what was written, the
names follow the model, and non-linear secondaries are refused by name."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import loadmat

import railride as rr
from railride.frequency.linear import linear_model


def _ideal(name):
    return rr.Suspension.named(name, damper="ideal")


def test_mat_file_round_trip(tmp_path):
    model = linear_model(None, _ideal("pid"))
    path = tmp_path / "pid.mat"
    model.to_mat(path)
    data = loadmat(path)
    for key in "ABCD":
        assert np.array_equal(data[key], getattr(model, key))
    names = [str(c[0][0]) for c in data["state_names"]]
    assert names == list(model.states)
    assert names[-3:] == ["carbody_bounce_integral", "carbody_pitch_integral", "carbody_roll_integral"]
    assert [str(c[0][0]) for c in data["output_units"]][: len(rr.vehicle.DOF_NAMES)] == list(rr.vehicle.DOF_UNITS)
    assert str(data["secondary"][0]) == "pid"


def test_python_control_state_space_has_the_names_and_the_response():
    """python-control evaluates the transfer function its own way: the same numbers."""
    control = pytest.importorskip("control")
    model = linear_model(None, _ideal("sas-attitude-ride"))
    sys = model.to_control()
    assert isinstance(sys, control.StateSpace)
    assert list(sys.state_labels) == list(model.states)
    assert list(sys.input_labels) == list(model.inputs)
    assert list(sys.output_labels) == list(model.outputs)
    f = np.array([0.7, 1.3, 9.0])
    ours = model.frequency_response(f)
    theirs = np.moveaxis(np.asarray(sys(2j * np.pi * f)), -1, 0)
    assert np.allclose(ours, theirs, rtol=1e-8, atol=1e-10 * np.abs(ours).max())


def test_plant_has_force_inputs_and_no_dashpots():
    """Without the dashpots the secondary corners feel only the springs: the plant's damping
    is the passive one less c_sz T T^T, and a unit corner force moves the carbody by T / M."""
    plant, passive = linear_model(None, "plant"), linear_model(None, "passive")
    vehicle = rr.Vehicle()
    minv = 1.0 / np.diag(vehicle.M)
    c_sz = vehicle.params.c_sz
    assert np.allclose(plant.A[9:, 9:] - passive.A[9:, 9:], minv[:, None] * c_sz * vehicle.T @ vehicle.T.T)
    force = plant.index("inputs", "secondary_force_1R")
    assert np.allclose(plant.B[9:, force], minv * vehicle.T[:, 0])


@pytest.mark.parametrize(
    "suspension, fragment",
    [
        (lambda: rr.Suspension.named("sas-attitude"), "not linear"),
        (lambda: rr.Suspension.named("sas-attitude", damper="ideal-damper"), "not linear"),
        (lambda: rr.Suspension.named("mr", voltage=1.0), "not linear"),
        (lambda: _ideal("pid").with_delay(2), "delay"),
        (lambda: "skyhook", "must be 'passive', 'plant' or a Suspension"),
    ],
)
def test_non_linear_secondaries_are_refused(suspension, fragment):
    with pytest.raises(ValueError, match=fragment):
        linear_model(None, suspension())


def test_ride_spectrum_refuses_what_it_cannot_compute():
    from railride.frequency.ride_spectrum import ride_spectrum

    with pytest.raises(ValueError, match="controllers = 'passive-on': not a linear suspension"):
        ride_spectrum("fra4", controllers="passive,passive-on")
    with pytest.raises(ValueError, match="track = 'fra9'"):
        ride_spectrum("fra9")
    with pytest.raises(ValueError, match="max_wavelength"):
        ride_spectrum("fra4", min_wavelength=10.0, max_wavelength=5.0)
    with pytest.raises(ValueError, match="unstable"):
        ride_spectrum("fra4", controllers="groundhook", points=32)


def test_ride_spectrum_result_protocol(tmp_path):
    import json

    from railride.frequency.ride_spectrum import ride_spectrum

    result = ride_spectrum("german-low", speed=40.0, controllers="passive,skyhook", points=64)
    doc = result.to_dict()
    assert doc["schema"] == "railride.ride-spectrum/1"
    assert set(doc["weighted_rms_m_s2"]) == {"passive", "skyhook"}
    frame = result.to_pandas()
    assert len(frame) == 2 * 10 and frame["rms"].gt(0).all()
    paths = result.save(tmp_path / "out")
    assert json.loads(paths[0].read_text())["settings"]["track"] == "german-low"
    assert {p.name for p in paths} >= {"ride_spectrum.csv", "ride_spectrum_psd.csv"}
