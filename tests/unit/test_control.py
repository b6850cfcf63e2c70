"""Controllers: the decoupling transformation, the semi-active voltage law, timing, gains files."""

import re

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from railride import dampers
from railride.secondary.control import (
    PID,
    SAS,
    Attitude,
    GainSet,
    InnerLoop,
    Ride,
    SensorNoise,
    carbody_map,
    decoupling,
)
from railride.model.params import VehicleParams
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.model.track import scenario
from railride.model.vehicle import Vehicle

P = VehicleParams.preset("paper")
V = Vehicle(P)


@settings(max_examples=40, deadline=None)
@given(l=st.floats(2.0, 15.0), d_s=st.floats(0.5, 1.5))
def test_decoupling_is_a_right_inverse_for_any_geometry(l, d_s):
    veh = Vehicle(P.replace(l=l, d_s=d_s))
    Tc, Tp = carbody_map(veh), decoupling(veh)
    assert np.allclose(Tc @ Tp, np.eye(3), atol=1e-12)


def test_pure_demands_spread_over_the_corners_as_expected():
    Tp = decoupling(V)  # corners 1R, 1L, 2R, 2L; columns heave, pitch, roll
    heave, pitch, roll = Tp[:, 0], Tp[:, 1], Tp[:, 2]
    assert np.allclose(heave, 0.25)
    # pitch: front (bogie 1, x = +l) against rear; a positive pitch moment lowers the front
    assert np.allclose(pitch, np.array([-1, -1, 1, 1]) / (4 * P.l))
    # roll: left against right; a positive roll moment raises the left side
    assert np.allclose(roll, np.array([-1, 1, -1, 1]) / (4 * P.d_s))


def test_attitude_loop_with_modal_gains_in_proportion_equals_corner_pd():
    # T_c T_c^T = diag(4, 4 l^2, 4 d_s^2), so T_c^+ diag(4k, 4k l^2, 4k d_s^2) = k T_c^T
    k, c = 1.3e5, 7e4
    att = Attitude(
        kp_z=4 * k,
        kd_z=4 * c,
        kp_phi=4 * k * P.l**2,
        kd_phi=4 * c * P.l**2,
        kp_theta=4 * k * P.d_s**2,
        kd_theta=4 * c * P.d_s**2,
    )
    G_sas, _ = SAS(att).gains(V)
    G_pid, H_pid = PID(kp=k, ki=0.0, kd=c).gains(V)
    assert np.allclose(G_sas, G_pid) and np.all(H_pid == 0)


def test_ride_loop_acts_on_its_own_corner_only():
    # the corner's own motion by hand (docs/model.md), not through carbody_map, which the loop
    # itself uses: corner i at x = +-l (bogie 1 in front), y = +-d_s (L: +), its carbody point
    # moving by z - x phi + y theta (positive pitch lowers the front, positive roll raises the left)
    ride = Ride(kp_1R=0, kp_1L=2e4, kp_2R=0, kp_2L=0, kd_1R=0, kd_1L=0, kd_2R=3e3, kd_2L=0)
    zero = Attitude(0, 0, 0, 0, 0, 0)
    G, _ = SAS(zero, ride).gains(V)
    q = np.array([0.01, 0.002, -0.003])  # heave, pitch, roll
    rate = np.array([0.05, -0.01, 0.02])
    f = G @ np.concatenate([q, rate])
    z_1L = q[0] - P.l * q[1] + P.d_s * q[2]  # x = +l, y = +d_s
    v_2R = rate[0] + P.l * rate[1] - P.d_s * rate[2]  # x = -l, y = -d_s
    assert f == pytest.approx([0.0, -2e4 * z_1L, -3e3 * v_2R, 0.0], rel=1e-12, abs=1e-9)


SINE = scenario("paper-sine", duration=3.0)


def test_voltage_stays_in_range_and_is_minimal_when_the_demand_opposes_the_damper():
    g = GainSet.default()
    noise = SensorNoise(1e-3, 1e-4, 5e-3, 5e-4, seed=7)
    ds = simulate(
        SINE,
        suspension=[Suspension.named(n, g, sensor_noise=noise) for n in ("pid", "sas-attitude-ride")],
        solver=SolverSettings(output_rate=10000),
    ).dataset
    d = dampers.RAILWAY
    v = ds.damper_command_voltage.values
    assert v.min() >= d.v_min and v.max() <= d.v_max
    assert v.max() == d.v_max and (v == d.v_min).any()  # both limits are reached
    # a demand against the force the damper gives would need it to push energy in
    against = ds.damper_demand_force.values * ds.secondary_damper_force.values <= 0
    assert against.any() and np.all(v[against] == d.v_min)


def test_all_gains_zero_is_passive_off():
    zero = PID(0.0, 0.0, 0.0)
    a = simulate(SINE, suspension=Suspension.semi_active(controller=zero)).dataset
    b = simulate(SINE, suspension=Suspension.semi_active("railway", voltage=0.0)).dataset
    for name in ("carbody_bounce", "carbody_roll", "secondary_damper_force", "damper_voltage"):
        assert np.array_equal(a[name].values, b[name].values), name
    assert np.all(a.damper_command_voltage.values == 0.0)


#: the paper's sine long enough for the closed loops to settle (within 1 % by 10 s), one period
#: of it (60 m at 55.56 m/s), and the bump long enough to watch the motion die away after it
SETTLING_SINE = scenario("paper-sine", duration=12.0)
SINE_PERIOD = 60.0 / 55.56


@pytest.mark.parametrize(
    "sc, settles",
    [(SETTLING_SINE, "periodic"), (scenario("bump", duration=6.0), "decaying")],
    ids=["paper-sine", "bump"],
)
def test_every_controller_keeps_the_response_bounded(sc, settles):
    g = GainSet.default()
    names = ("pid", "sas-attitude", "sas-attitude-ride")
    ds = simulate(sc, suspension=[Suspension.named(n, g) for n in names]).dataset
    passive_off = simulate(sc, suspension=Suspension.semi_active("railway", voltage=0.0)).dataset
    # within twice the uncontrolled (0 V) response, or a small floor where that is ~0 (the
    # corner-specific ride gains roll the carbody a little even on a symmetric bump)
    for name, floor in (("carbody_bounce", 1e-3), ("carbody_pitch", 1e-3), ("carbody_roll", 1e-3)):
        bound = max(2 * float(abs(passive_off[name]).max()), floor)
        assert float(abs(ds[name]).max()) < bound, name

    # and no growing oscillation: the MR dampers can only take energy out, so a stable closed
    # loop under the periodic sine settles to a periodic response (the peak of the last input
    # period that of the one before), and after the bump (its last wheelset off it at 0.73 s)
    # the motion, fed no more, dies away (each second's peak below the one before)
    def peak(name, start, end):  # per controller
        return abs(ds[name].sel(time=slice(start, end))).max("time").values

    responses = ("carbody_acceleration", "carbody_bounce", "carbody_pitch")
    if settles == "periodic":
        end = float(ds.time[-1])
        for name in (*responses, "carbody_roll"):
            last, before = peak(name, end - SINE_PERIOD, end), peak(name, end - 2 * SINE_PERIOD, end - SINE_PERIOD)
            np.testing.assert_allclose(last, before, rtol=0.02, err_msg=name)
    else:
        for name in responses:
            peaks = np.array([peak(name, s, s + 1.0) for s in range(1, 6)])  # (second, controller)
            assert (np.diff(peaks, axis=0) < 0).all(), (name, peaks)


@pytest.mark.parametrize("rate", [1000.0, 500.0])
def test_a_step_demand_appears_one_controller_period_later_and_is_held(rate):
    kp, z0 = 1e5, 0.01
    state = np.zeros(18)
    state[0] = z0  # carbody lifted at t = 0, level track
    ds = simulate(
        scenario("paper-sine", amplitude=0.0, duration=0.01),
        suspension=Suspension.semi_active(controller=PID(kp, 0.0, 0.0)),
        solver=SolverSettings(control_rate=rate, output_rate=10000),
        initial_state=state,
    ).dataset
    fd = ds.damper_demand_force.values  # (time, corner)
    t = ds.time.values
    period = 1.0 / rate
    before = t < period - 1e-12
    assert np.all(fd[before] == 0.0)  # nothing computed yet
    first = np.isclose(t, period)
    assert np.allclose(fd[first], -kp * z0, rtol=1e-12)  # the sample taken at t = 0
    held = (t >= period - 1e-12) & (t < 2 * period - 1e-12)
    assert np.all(fd[held] == fd[first])  # held until the next sample takes effect
    second = np.isclose(t, 2 * period)
    z_at_period = ds.carbody_bounce.values[first][0]
    assert np.allclose(fd[second], -kp * z_at_period, rtol=1e-9)


def test_sensor_noise_is_seeded():
    g = GainSet.default()

    def run(seed):
        noise = SensorNoise(1e-3, 1e-4, 1e-3, 1e-4, seed=seed)
        return simulate(
            scenario("paper-sine", duration=1.0), suspension=Suspension.named("pid", g, sensor_noise=noise)
        ).dataset

    a, b, c = run(1), run(1), run(2)
    assert np.array_equal(a.carbody_bounce.values, b.carbody_bounce.values)
    assert not np.array_equal(a.carbody_bounce.values, c.carbody_bounce.values)


def test_gains_file_round_trip(tmp_path):
    g = GainSet.default()
    path = tmp_path / "gains.toml"
    path.write_text(g.to_toml())
    back = GainSet.load(path)
    assert (back.inner, back.pid, back.attitude, back.ride) == (g.inner, g.pid, g.attitude, g.ride)


@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda t: t.replace("kd = ", "# kd = "), r"missing entry 'kd' in \[pid\]"),
        (lambda t: t.replace("[pid]\n", "[pid]\nkf = 1.0\n"), r"unknown entry 'kf' in \[pid\]"),
        (
            lambda t: re.sub(r"kp_z = [0-9.e+]+", 'kp_z = "high"', t),
            r"entry 'kp_z' in \[sas.attitude\] = 'high' is not a number",
        ),
        (lambda t: re.sub(r"kd_2L = [0-9.e+]+", "kd_2L = -5.0", t), r"\[sas.ride\] SAS ride gain 'kd_2L' = -5.0"),
        (lambda t: t.replace("[inner]", "[inner2]"), r"unknown table"),
        (lambda t: t + "\n[[", r"not valid TOML"),
    ],
)
def test_bad_gains_files_name_the_entry(tmp_path, edit, match):
    text = edit(GainSet.default().to_toml())
    with pytest.raises(ValueError, match=match):
        GainSet.from_toml(text, source="g.toml")


def test_controller_input_errors():
    with pytest.raises(ValueError, match="unknown controller 'lqr'"):
        GainSet.default().controller("lqr")
    with pytest.raises(ValueError, match="either voltage"):
        Suspension.semi_active(controller=PID(1, 0, 0), voltage=1.0)
    with pytest.raises(ValueError, match="control_rate"):
        simulate(
            SINE, suspension=Suspension.semi_active(controller=PID(1, 0, 0)), solver=SolverSettings(control_rate=3000.0)
        )
    with pytest.raises(ValueError, match="closed loop only"):
        Suspension(inner=InnerLoop(1.0, 1e-3))
    with pytest.raises(ValueError, match="PID gain 'kp' = -1"):
        PID(-1.0, 0.0, 0.0)
