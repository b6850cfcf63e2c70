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
    """Without the dashpots the secondary corners feel only the springs: the plant's damping is
    that of the vehicle assembled element by element with c_sz = 0 (not the passive one less
    c_sz T T^T: that difference is the code's own subtraction, and holds whatever T or C0 is),
    its springs the passive vehicle's; and a unit force at corner 1R accelerates the bodies as
    the geometry of docs/model.md says, by hand."""
    plant, passive = linear_model(None, "plant"), linear_model(None, "passive")
    p = rr.VehicleParams.preset("paper")
    # the DOFs: carbody, bogie 1, bogie 2, each bounce, pitch, roll
    inertia = np.array([p.m_c, p.I_cy, p.I_cx, p.m_b, p.I_by, p.I_bx, p.m_b, p.I_by, p.I_bx])
    undamped = rr.Vehicle(p.replace(c_sz=0.0)).C
    scale = np.abs(rr.Vehicle(p).C).max() / inertia.min()
    np.testing.assert_allclose(plant.A[9:, 9:], -undamped / inertia[:, None], rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(passive.A[9:, 9:], -rr.Vehicle(p).C / inertia[:, None], rtol=0, atol=1e-12 * scale)
    np.testing.assert_array_equal(plant.A[9:, :9], passive.A[9:, :9])  # the springs stay
    # corner 1R sits at x = +l, y = -d_s over bogie 1's centre; positive pitch lowers the front,
    # positive roll raises the left side: a unit force up on the carbody is heave 1, pitch
    # -l, roll -d_s, and down on bogie 1 at y = -d_s is bounce -1, roll +d_s
    force = plant.index("inputs", "secondary_force_1R")
    moment = np.array([1.0, -p.l, -p.d_s, -1.0, 0.0, p.d_s, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(plant.B[9:, force], moment / inertia, rtol=1e-12, atol=0)
    assert not plant.B[:9, force].any()  # a force moves no position at once


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


def test_a_closed_loop_records_the_gains_it_closed_with(tmp_path):
    """The document and the .mat name the gains of the loop their matrices hold: the state
    matrix changes with a gain, and the record with it."""
    import json

    from railride.secondary.control import GainSet
    from railride.secondary.suspension import Suspension
    from railride.frequency.linear import linear_model

    gains = GainSet.default()
    model = linear_model("paper", Suspension.named("pid", gains, damper="ideal"))
    assert model.to_dict()["controller"] == {"name": "pid", "gains": gains.pid.to_dict()}
    softer = gains.apply({"pid.kp": gains.pid.kp / 2})
    other = linear_model("paper", Suspension.named("pid", softer, damper="ideal"))
    assert other.to_dict()["controller"]["gains"]["kp"] == gains.pid.kp / 2
    assert not np.array_equal(other.A, model.A)
    assert linear_model("paper").to_dict()["controller"] is None
    model.to_mat(tmp_path / "m.mat")
    mat = loadmat(tmp_path / "m.mat")
    assert json.loads(str(mat["controller_gains"][0]))["gains"]["kd"] == gains.pid.kd
    assert json.loads(str(mat["versions"][0]))["railride"] == str(mat["railride_version"][0])


def test_the_command_says_where_a_closed_loops_gains_came_from(tmp_path):
    """state-space names the gains file of a closed loop and says when the study that made it
    did not tune this law (its start values)."""
    import json

    from clihelp import ok

    doc = json.loads(ok("state-space", "--suspension", "pid", "--format", "json").stdout)
    assert doc["gains_source"] == "gains railride/data/gains.toml"
    assert "gains_source" not in json.loads(ok("state-space", "--format", "json").stdout)
    tuned = tmp_path / "t"
    ok("tune", "--controllers", "skyhook", "--budget", 25, "--values", 3, "--duration", 0.3, "--out", tuned)
    doc = json.loads(
        ok("state-space", "--suspension", "pid", "--gains", tuned / "gains.toml", "--format", "json").stdout
    )
    assert doc["gains_source"].endswith("pid was not tuned by the study that made them: its start values")


def test_bad_arguments_of_the_linear_tools_name_the_argument_and_what_is_allowed():
    from railride.errors import InputError

    lm = linear_model("paper")
    with pytest.raises(InputError, match=r"kind = 'output': allowed states, inputs, outputs"):
        lm.index("output", "carbody_bounce")
    with pytest.raises(InputError, match=r"frequency_hz = '1 Hz': must be a number or a 1-D array"):
        lm.frequency_response("1 Hz")
    car = rr.Vehicle("paper")
    for rails in ((1, 1, 1), 5, ("a", 1)):
        with pytest.raises(InputError, match=r"rails = .*: allowed 'in-phase', 'anti-phase' or a pair"):
            car.frequency_response([1.0], 20.0, rails)
