"""The ideal actuator (`Suspension.ideal`, damper "ideal"): the corner force is the outer loop's held demand.

Checked against the recorded states (the demand is G m + H xi of the previous controller sample,
held for a period) and against a linear closed-loop model assembled here from the vehicle
matrices and integrated by scipy's solve_ivp."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from railride import dampers

from railride.run import rig
from railride.cli import app
from railride.studies.comparison import compare
from railride.secondary.control import PID, SAS, Attitude, GainSet, ZeroDemand
from railride.model.params import VehicleParams
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.model.track import CosineBump, Scenario
from railride.model.vehicle import Vehicle
from clihelp import runner

PARAMS = VehicleParams.preset("paper")
#: bump on the left rail only: heave, pitch and roll all move
BUMP = Scenario(CosineBump(height=0.02, length=10.0, start=5.0, rails="left"), speed=40.0, duration=1.5, name="bump")


def _carbody(ds) -> np.ndarray:
    return np.column_stack([ds["carbody_bounce"], ds["carbody_pitch"], ds["carbody_roll"]])


# -- (a) the force is the held demand ---------------------------------------------------------
@pytest.fixture(scope="module")
def ideal_batch():
    """PID, SAS attitude, SAS attitude+ride on the ideal actuator, controller at 250 Hz (four
    output samples a period, so the hold shows in the 1 kHz record). The neutral reference gains:
    stable on the ideal actuator at this slow rate, whatever gains are shipped."""
    g = GainSet.reference()
    ctrls = [g.controller(n) for n in ("pid", "sas-attitude", "sas-attitude-ride")]
    res = simulate(BUMP, PARAMS, [Suspension.ideal(c) for c in ctrls], solver=SolverSettings(control_rate=250.0))
    return ctrls, res.dataset


def test_ideal_force_equals_the_held_demand_exactly(ideal_batch):
    _, ds = ideal_batch
    f = ds["secondary_damper_force"].values
    fd = ds["damper_demand_force"].values
    assert np.abs(fd).max() > 100.0  # the controllers do ask for force on this bump
    np.testing.assert_array_equal(f, fd)


def test_ideal_dataset_has_no_voltage_or_damper_state_channels(ideal_batch):
    _, ds = ideal_batch
    for name in ("damper_voltage", "damper_command_voltage", "damper_hysteretic_z", "damper_internal_displacement"):
        assert name not in ds
    assert json.loads(ds.attrs["damper"])["model"] == "ideal"
    assert json.loads(ds.attrs["inner_loop"]) is None  # no inner loop in use


def test_ideal_demand_is_the_previous_sample_held_for_a_period(ideal_batch):
    """f_d in effect over [t_k, t_k+1) = G m(t_k-1) + H xi(t_k-1), from the recorded carbody
    states; the integral by the rectangle rule over the samples up to t_k-1. Nothing is
    demanded in the first period."""
    ctrls, ds = ideal_batch
    vehicle = Vehicle(PARAMS)
    per = 4  # output samples per controller period (1 kHz / 250 Hz)
    tc = 1.0 / 250.0
    for i, ctrl in enumerate(ctrls):
        part = ds.isel(sample=i)
        G, H = ctrl.gains(vehicle)
        m = np.column_stack(
            [
                _carbody(part),
                part["carbody_bounce_velocity"],
                part["carbody_pitch_velocity"],
                part["carbody_roll_velocity"],
            ]
        )
        ticks = m[::per]  # the states the controller sampled
        xi = tc * np.cumsum(ticks[:, :3], axis=0)
        expected = ticks @ G.T + xi @ H.T  # computed at tick k, in effect from tick k + 1
        fd = part["damper_demand_force"].values
        held = np.repeat(np.vstack([np.zeros((1, 4)), expected[:-1]]), per, axis=0)[: len(fd)]
        scale = np.abs(fd).max()
        np.testing.assert_allclose(fd, held, rtol=0, atol=1e-9 * scale)


def test_ideal_without_an_outer_loop_applies_no_force():
    res = simulate(BUMP, PARAMS, [Suspension.ideal(ZeroDemand())], solver=SolverSettings(control_rate=1000.0))
    assert np.all(res.dataset["secondary_damper_force"].values == 0.0)


# -- (b) independent check: a linear closed-loop model under solve_ivp -----------------------------
def test_ideal_skyhook_matches_a_linear_closed_loop_model_integrated_by_solve_ivp():
    """SAS attitude loop with derivative gains only (skyhook on heave, pitch and roll: the
    passive secondary damping, c_sz at each corner, moved to the inertial frame) on the ideal
    actuator, controller at 1/dt. The reference is

        M q'' + C0 q' + K q = -(K_w w + C_w w') + T G m,   m = (q_c, q_c'),

    assembled here from the vehicle matrices, with the rails re-evaluated from the track, and
    integrated by solve_ivp (DOP853, rtol 1e-10).

    Tolerance, from the delay: the stepper applies over [t_n, t_n + dt) the demand computed at
    t_n - dt, so its force lags the continuous law by dt to 2 dt, 1.5 dt on average: to first
    order f = G m - 1.5 dt G m'. The response to that difference, dq, solves the same linear
    closed loop forced by -1.5 dt T G m' (integrated alongside). The test asks that (1) the
    stepper's carbody response lies within 1.5 max|dq| of the reference (about 1e-3 of the
    response at dt = 1e-4 s) and (2) subtracting dq leaves under 5 % of it: the whole
    difference is the one-period delay and the hold, nothing else. The uncontrolled vehicle
    (G = 0) differs from the reference by the order of the response itself."""
    dt = 1e-4
    vehicle = Vehicle(PARAMS)
    c = 4 * PARAMS.c_sz  # the passive secondary damping of the whole car, in heave
    l, d_s = float(vehicle.T[1, 2]), float(vehicle.T[2, 1])  # rear pitch arm, left roll arm
    ctrl = SAS(Attitude(kp_z=0.0, kd_z=c, kp_phi=0.0, kd_phi=c * l**2, kp_theta=0.0, kd_theta=c * d_s**2))
    ds = simulate(BUMP, PARAMS, Suspension.ideal(ctrl), solver=SolverSettings(dt=dt, control_rate=1.0 / dt)).dataset
    t = ds["time"].values

    M, K, C0, Kw, Cw, T = vehicle.M, vehicle.K, vehicle.C0, vehicle.K_w, vehicle.C_w, vehicle.T
    Minv = np.linalg.inv(M)
    G, _ = ctrl.gains(vehicle)
    Gs = np.zeros((4, 18))  # G on the full state (q, q'): m = (q[0:3], q'[0:3])
    Gs[:, 0:3], Gs[:, 9:12] = G[:, :3], G[:, 3:]
    lag, V = vehicle.wheelset_lag_distance, BUMP.speed
    delay = 1.5 * dt

    def rails(time):
        zl, zr, dzl, dzr = BUMP.track.evaluate(V * time - lag)
        w, wd = np.empty(8), np.empty(8)
        w[0::2], w[1::2] = zl, zr
        wd[0::2], wd[1::2] = V * dzl, V * dzr
        return w, wd

    def rhs(time, x, gain):
        q, v, dq, dv = x[:9], x[9:18], x[18:27], x[27:]
        w, wd = rails(time)
        a = Minv @ (-(K @ q + C0 @ v) - (Kw @ w + Cw @ wd) + gain * (T @ (Gs @ x[:18])))
        rate = np.concatenate([v, a])
        # first-order effect of the delay: forced by -delay G m'
        da = Minv @ (-(K @ dq + C0 @ dv) + gain * (T @ (Gs @ x[18:] - delay * (Gs @ rate))))
        return np.concatenate([rate, dv, da])

    def integrate(gain):
        sol = solve_ivp(
            rhs,
            (0.0, t[-1]),
            np.zeros(36),
            method="DOP853",
            rtol=1e-10,
            atol=1e-14,
            t_eval=t,
            args=(gain,),
            max_step=0.005,
        )
        assert sol.success
        return sol.y[:3].T, sol.y[18:21].T

    ref, dq = integrate(1.0)
    uncontrolled, _ = integrate(0.0)
    sim = _carbody(ds)
    scale = np.abs(ref).max(axis=0)
    err = np.abs(sim - ref).max(axis=0)
    bound = 1.5 * np.abs(dq).max(axis=0)
    assert np.all(bound < 2e-3 * scale)  # the delay is small at 1/dt
    assert np.all(err <= bound), (err / scale, bound / scale)
    assert np.all(np.abs(sim - ref - dq).max(axis=0) < 0.05 * np.abs(dq).max(axis=0))
    assert np.all(np.abs(uncontrolled - ref).max(axis=0) > 100 * bound)


# -- compare ----------------------------------------------------------------------------------
def test_compare_with_the_ideal_actuator_records_it_and_has_no_voltages():
    res = compare(BUMP, PARAMS, controllers=["passive", "sas-attitude"], damper="ideal")
    doc = res.to_dict()
    assert doc["settings"]["damper"] == "ideal" and doc["settings"]["damper_scale"] == 1.0
    rows = {r["name"]: r for r in doc["controllers"]}
    assert "voltage_mean_v" not in rows["sas-attitude"]["damper"]
    assert rows["sas-attitude"]["damper"]["force_max_n"] > 0
    # passive stays the viscous baseline
    passive = simulate(BUMP, PARAMS).dataset
    np.testing.assert_array_equal(res.datasets["passive"]["carbody_bounce"], passive["carbody_bounce"])


# -- (c) bad input ------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"damper": "ideal"}, "ideal.*controller"),
        ({"damper": "ideal", "voltage": 1.0}, "ideal.*controller.*voltage"),
        ({"damper": dampers.Ideal()}, "ideal.*controller"),
        ({"damper": "ideal", "voltage": 1.0, "controller": PID(1.0, 0.0, 1.0)}, "either voltage"),
    ],
)
def test_ideal_actuator_without_a_controller_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):  # the suspension's checks, at construction
        Suspension(**kwargs)


def test_the_rig_refuses_the_ideal_actuator():
    with pytest.raises(ValueError, match="ideal actuator"):
        rig.drive("ideal", rig.SineMotion(0.01, 1.0), duration=0.1, voltage=0.0)
    with pytest.raises(ValueError, match="ideal actuator"):
        rig.cycles(dampers.Ideal(), 0.01, 1.0, [0.0])
    with pytest.raises(ValueError, match="ideal actuator"):
        rig.track("ideal")


def test_the_ideal_actuator_has_no_force_capacity_to_scale():
    with pytest.raises(ValueError, match="factor.*ideal"):
        dampers.preset("ideal").scaled(2.0)
    with pytest.raises(ValueError, match="damper_scale = 2.*ideal"):
        compare(BUMP, PARAMS, damper="ideal", damper_scale=2.0)


def _input_error(args, *fragments):
    result = runner.invoke(app, [str(a) for a in args])
    assert result.exit_code == 2, (result.exit_code, result.stdout, result.stderr)
    assert isinstance(result.exception, SystemExit), result.exception  # CliRunner hides tracebacks
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    assert "Traceback" not in result.output and result.stdout == ""
    for fragment in fragments:
        assert fragment in lines[0], lines[0]


@pytest.mark.parametrize(
    "args, fragments",
    [
        (("simulate", "--suspension", "mr", "--damper", "ideal"), ("--damper = 'ideal'", "controller")),
        (
            ("damper", "--damper", "ideal", "--amplitude", 0.01, "--frequency", 1, "--voltage", 0),
            ("--damper = 'ideal'", "rig", "allowed: dyke1996, railway, spencer1997"),
        ),
        (("tracking", "--model", "ideal"), ("--damper = 'ideal'", "rig")),
        (("compare", "--damper", "ideal", "--damper-scale", 2), ("--damper-scale = 2", "ideal")),
        (("sweep", "--suspension", "mr,pid", "--damper", "ideal"), ("--damper = 'ideal'", "mr")),
        (("sweep", "--suspension", "pid", "--damper", "ideal", "--damper-scale", "1,2"), ("--damper-scale", "ideal")),
        (("compare", "--damper", "ideal2"), ("--damper = 'ideal2'", "unknown damper model", "ideal")),
    ],
)
def test_cli_ideal_actuator_input_errors(args, fragments):
    _input_error(args, *fragments)


def test_cli_compare_with_the_ideal_actuator(tmp_path):
    result = runner.invoke(
        app,
        [
            "compare",
            "--damper",
            "ideal",
            "--controllers",
            "sas-attitude",
            "--duration",
            "1",
            "--format",
            "json",
            "--out",
            str(tmp_path / "c"),
        ],
    )
    assert result.exit_code == 0, result.stderr
    doc = json.loads(result.stdout)
    assert doc["settings"]["damper"] == "ideal"
    header = (tmp_path / "c" / "compare.csv").read_text().splitlines()[0].split(",")
    assert "damper_demand_force_1R" in header
    assert not any(c.startswith("damper_command_voltage") for c in header)
    row = next(r for r in doc["controllers"] if r["name"] == "sas-attitude")
    assert set(row["damper"]) == {
        "force_rms_n",
        "force_max_n",
        "travel_rms_m",
        "travel_max_m",
        "clearance_m",
        "stop_stiffness_n_per_m",
        "reached_stops",
        "demand_rms_n",
        "demand_max_n",
    }
    table = runner.invoke(app, ["compare", "--damper", "ideal", "--controllers", "sas-attitude", "--duration", "1"])
    assert table.exit_code == 0, table.stderr
    assert "ideal actuators (force = demand)" in table.stdout


# -- the ideal semi-active damper ("ideal-damper"): the demand where it dissipates ------------
def test_ideal_damper_applies_the_demand_only_where_it_dissipates():
    g = GainSet.reference()
    ctrls = [g.controller(n) for n in ("pid", "sas-attitude", "sas-attitude-ride")]
    ds = simulate(
        BUMP, PARAMS, [Suspension.ideal(c, dissipative=True) for c in ctrls], solver=SolverSettings(control_rate=250.0)
    ).dataset
    f = ds["secondary_damper_force"].values
    fd = ds["damper_demand_force"].values
    xd = ds["secondary_deflection_velocity"].values
    on = f != 0.0
    # where it acts, the force is the demand exactly; it never puts energy in (f x' <= 0)...
    np.testing.assert_array_equal(f[on], fd[on])
    assert (f * xd).max() <= 0.0
    # ... and it is off exactly where the demand would have pushed energy in
    np.testing.assert_array_equal(~on & (fd != 0.0), fd * xd > 0.0)
    # both happen on this bump, so the test can tell the clipped law from the plain one
    assert 0.1 < on.mean() < 0.9
    assert json.loads(ds.attrs["damper"])["model"] == "ideal-damper"
