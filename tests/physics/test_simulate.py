"""The compiled stepper against independent solutions: a NumPy reference, the frequency
domain, an analytic single-mass decay, energy conservation, symmetry and step halving."""

import numpy as np
import pytest

from railride.model.params import VehicleParams
from railride.testing.reference import simulate_reference
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.model.track import CosineBump, Scenario, SineTrack, scenario
from railride.model.vehicle import DOF_NAMES, Vehicle

P = VehicleParams.preset("paper")
BUMP = Scenario(CosineBump(height=0.02, length=10.0, start=5.0, rails="left"), speed=40.0, duration=1.5, name="bump")


def _q(ds):
    return np.stack([ds[name].values for name in DOF_NAMES], axis=-1)


def test_compiled_stepper_equals_the_numpy_reference():
    ref = simulate_reference(BUMP, P, dt=1e-4, output_every=10)
    ds = simulate(BUMP, P, solver=SolverSettings(dt=1e-4, output_rate=1000)).dataset
    q = _q(ds)
    assert np.allclose(ds.time.values, ref["time"])
    scale = np.abs(ref["q"]).max(axis=0)
    assert np.all(scale > 0)
    assert np.abs(q - ref["q"]).max(axis=0) / scale == pytest.approx(np.zeros(9), abs=1e-6)
    # the reference evaluates the profile exactly, the stepper interpolates its table: heights
    # to O(Delta^4), rail velocities (which reach the acceleration through c_pz) to O(Delta^3)
    acc = ds["carbody_acceleration"].values
    assert np.abs(acc - ref["carbody_acceleration"]).max() < 1e-5 * np.abs(acc).max()


def test_batch_equals_the_single_runs():
    scen = [scenario("paper-sine", duration=2.0), BUMP.__class__(BUMP.track, 40.0, 2.0, "bump")]
    pars = [P, P.replace(c_sz=4e4, m_c=3.5e4)]
    batch = simulate(scen, pars, solver=SolverSettings(dt=1e-4)).dataset
    assert batch.sizes["sample"] == 2
    for i in range(2):
        single = simulate(scen[i], pars[i], solver=SolverSettings(dt=1e-4)).dataset
        for name in (
            "carbody_bounce",
            "carbody_roll",
            "carbody_acceleration",
            "secondary_damper_force",
            "rail_displacement",
        ):
            assert np.allclose(batch[name].isel(sample=i).values, single[name].values, rtol=1e-12, atol=0), name


def test_steady_state_sine_response_equals_the_frequency_response():
    sc = scenario("paper-sine")  # A = 0.05 m, lambda = 60 m, psi = 90 deg, 55.56 m/s, 10 s
    ds = simulate(sc, P).dataset.sel(time=slice(6.0, 10.0))  # transients have died out
    A, lam, psi = sc.track.amplitude, sc.track.wavelength, np.deg2rad(sc.track.rail_phase_deg)
    f = sc.speed / lam
    frf = Vehicle(P).frequency_response(f, sc.speed, rails=(1.0, np.exp(-1j * psi)))
    t = ds.time.values
    for name in ("carbody_bounce", "carbody_pitch", "carbody_roll", "carbody_acceleration", "front_bogie_roll"):
        predicted = np.imag(A * frf[name].values[0] * np.exp(2j * np.pi * f * t))
        error = np.abs(ds[name].values - predicted).max()
        assert error < 0.01 * np.abs(predicted).max(), name


@pytest.mark.parametrize("track", [CosineBump(0.02, 10.0, 5.0, "left"), SineTrack(0.05, 60.0, 30.0)])
def test_fourth_order_convergence_under_step_halving(track):
    sc = Scenario(track, speed=40.0, duration=1.5)
    runs = {
        # the RK4 stepper (the passive default is the exact discretisation: tests/physics/test_exact.py)
        dt: simulate(sc, P, solver=SolverSettings(dt=dt, output_rate=250, method="rk4")).dataset
        for dt in (4e-4, 2e-4, 1e-4, 2.5e-5)
    }
    fine = runs[2.5e-5]
    errors = []
    for dt in (4e-4, 2e-4, 1e-4):
        errors.append(
            max(
                float(np.abs(runs[dt][c] - fine[c]).max() / np.abs(fine[c]).max())
                for c in ("carbody_bounce", "carbody_roll", "carbody_acceleration", "front_bogie_pitch")
            )
        )
    ratios = [errors[i] / errors[i + 1] for i in range(2)]
    for r in ratios:
        assert 12 < r < 20, (errors, ratios)  # 2^4 = 16 for fourth order
    assert errors[-1] < 1e-8  # the default step is far inside the accurate range


def test_symmetric_rails_excite_no_roll_and_antisymmetric_rails_no_bounce_or_pitch():
    same = simulate(scenario("paper-sine", rail_phase=0.0, duration=3.0)).dataset
    for name in ("carbody_roll", "front_bogie_roll", "rear_bogie_roll"):
        assert np.abs(same[name]).max() < 1e-12 * np.abs(same["carbody_bounce"]).max()
    opposite = simulate(scenario("paper-sine", rail_phase=180.0, duration=3.0)).dataset
    for name in ("carbody_bounce", "carbody_pitch", "front_bogie_bounce", "rear_bogie_pitch"):
        assert np.abs(opposite[name]).max() < 1e-9 * np.abs(opposite["carbody_roll"]).max()


def test_free_decay_of_the_carbody_on_a_stiff_primary_is_a_damped_oscillator():
    # Single-mass limit: bogies locked to level rails, carbody bounce on 4 k_sz and 4 c_sz.
    p = P.replace(k_pz=P.k_pz * 1e3, k_px=P.k_px * 1e3, k_py=P.k_py * 1e3, c_sz=1e4)
    x0 = 0.01
    state = np.zeros(18)
    state[0] = x0
    ds = simulate(scenario("paper-sine", amplitude=0.0, duration=5.0), p, initial_state=state).dataset
    omega = np.sqrt(4 * p.k_sz / p.m_c)
    zeta = 4 * p.c_sz / (2 * p.m_c * omega)
    wd = omega * np.sqrt(1 - zeta**2)
    t = ds.time.values
    exact = x0 * np.exp(-zeta * omega * t) * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta**2) * np.sin(wd * t))
    assert np.abs(ds["carbody_bounce"].values - exact).max() < 1e-3 * x0
    assert np.abs(ds["carbody_pitch"]).max() < 1e-12 and np.abs(ds["carbody_roll"]).max() < 1e-12


def test_dampers_dissipate_exactly_the_energy_the_vehicle_loses():
    veh = Vehicle(P)
    state = np.zeros(18)
    state[[0, 2, 4, 8]] = [0.02, 0.01, 0.003, -0.004]
    state[9 + 1] = 0.01
    ds = simulate(
        scenario("paper-sine", amplitude=0.0, duration=3.0),
        P,
        solver=SolverSettings(dt=1e-4, output_rate=10000),
        initial_state=state,
    ).dataset
    q, v = _q(ds), np.stack([ds[f"{n}_velocity"].values for n in DOF_NAMES], axis=-1)
    energy = 0.5 * np.einsum("ti,ij,tj->t", v, veh.M, v) + 0.5 * np.einsum("ti,ij,tj->t", q, veh.K, q)
    power = np.einsum("ti,ij,tj->t", v, veh.C, v)
    dissipated = np.concatenate([[0.0], np.cumsum(0.5 * (power[1:] + power[:-1]) * np.diff(ds.time.values))])
    assert np.all(np.diff(energy) <= 1e-12 * energy[0])  # never gains energy
    assert np.abs(energy[0] - energy - dissipated).max() < 1e-4 * energy[0]
    # the secondary dampers take power out at every instant
    assert np.all(ds["secondary_damper_force"] * ds["secondary_deflection_velocity"] <= 0)


def test_wheelsets_see_the_same_profile_delayed_by_their_spacing():
    ds = simulate(BUMP, P).dataset
    lag = Vehicle(P).wheelset_lag_distance
    t = ds.time.values
    h = BUMP.track.height
    # tolerances: the cosine bump's curvature jumps at its ends, where the cubic input
    # interpolation is second order only
    for j in range(4):
        zl, zr, dzl, _ = BUMP.track.evaluate(BUMP.speed * t - lag[j])
        assert np.abs(zl).max() == pytest.approx(h, rel=1e-3)
        assert np.abs(ds["rail_displacement"].sel(wheelset=j + 1, rail="L").values - zl).max() < 1e-5 * h
        assert np.abs(ds["rail_displacement"].sel(wheelset=j + 1, rail="R").values).max() == 0
        rate_error = np.abs(ds["rail_velocity"].sel(wheelset=j + 1, rail="L").values - BUMP.speed * dzl)
        scale = BUMP.speed * np.abs(dzl).max()
        assert rate_error.max() < 5e-3 * scale
        x = (BUMP.speed * t - lag[j] - BUMP.track.start) / BUMP.track.length
        interior = (x > 0.02) & (x < 0.98)
        assert rate_error[interior].max() < 1e-5 * scale


def test_result_channels_units_and_provenance():
    res = simulate(scenario("paper-sine", duration=1.0))
    ds = res.dataset
    assert ds["carbody_acceleration"].attrs["units"] == "m/s^2"
    assert ds["carbody_pitch"].attrs["units"] == "rad"
    assert ds.sizes["time"] == 1001 and ds.time.values[-1] == pytest.approx(1.0)
    assert list(ds.corner.values) == ["1R", "1L", "2R", "2L"]
    for key in ("railride_version", "numba_version", "numpy_version", "dt_s", "output_rate_hz"):
        assert key in ds.attrs
    assert '"wavelength_m": 60.0' in str(ds["scenario"].values)
    assert VehicleParams(**__import__("json").loads(str(ds["vehicle_params"].values))) == P
    # corner displacement is the carbody's own motion at the corner
    corner = ds["carbody_corner_displacement"].sel(corner="1L").values
    expected = ds["carbody_bounce"] - P.l * ds["carbody_pitch"] + P.d_s * ds["carbody_roll"]
    assert np.allclose(corner, expected.values, rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"dt": 0.05}, "too large"),
        ({"dt": 0.05, "output_rate": 20.0, "method": "rk4"}, "too large: fourth-order Runge-Kutta is unstable"),
        ({"dt": -1e-4}, "dt"),
        ({"dt": float("nan")}, "dt"),
        ({"output_rate": 3000.0}, "whole number of steps"),
        ({"scenario": "tgv"}, "unknown scenario"),
        ({"initial_state": [0.0] * 5}, "initial_state"),
        ({"scenario": [scenario(duration=1.0), scenario(duration=2.0)]}, "same duration"),
        ({"params": "tgv"}, "unknown vehicle preset"),
    ],
)
def test_bad_input_raises_a_clear_value_error(kwargs, match):
    kwargs.setdefault("scenario", scenario(duration=1.0))
    steps = {k: kwargs.pop(k) for k in ("dt", "output_rate", "method") if k in kwargs}
    with pytest.raises(ValueError, match=match):  # SolverSettings checks the steps, simulate the rest
        simulate(solver=SolverSettings(**steps) if steps else None, **kwargs)


def test_a_run_that_diverges_stops_and_says_so():
    with pytest.raises(RuntimeError, match="diverged"):
        # a rail 1e5 m high is refused as input now (track.MAX_RAIL_AMPLITUDE): start the
        # carbody past the divergence bound instead
        simulate(scenario("paper-sine", duration=1.0), initial_state=[2000.0] + [0.0] * 17)


# -- a run that diverges ------------------------------------------------------------------------
def test_a_diverged_sample_is_marked_and_the_others_stand():
    from railride.secondary.control import PID, GainSet

    g = GainSet.default()
    unstable = PID(kp=1e12, ki=0.0, kd=1e11)  # on the ideal actuator: far past any stable gain
    sc = scenario("paper-sine", duration=1.0)
    alone = simulate(sc, suspension=Suspension.ideal(g.pid)).metrics()
    res = simulate(sc, suspension=[Suspension.ideal(c) for c in (g.pid, unstable, g.pid)], on_divergence="mark")
    m = res.metrics()
    assert np.isnan(res.diverged_at[[0, 2]]).all() and 0 < res.diverged_at[1] < 1.0
    assert np.isnan(m.isel(sample=1).values).all()
    for i in (0, 2):  # the batch neighbours are untouched by the diverged sample
        np.testing.assert_array_equal(m.isel(sample=i, drop=True).values, alone.values)
    with pytest.raises(RuntimeError, match=r"diverged \(sample 1 at t = "):
        simulate(sc, suspension=[Suspension.ideal(g.pid), Suspension.ideal(unstable)])
    with pytest.raises(ValueError, match="on_divergence = 'skip'"):
        simulate(sc, on_divergence="skip")


def test_a_study_goes_on_past_a_diverged_run():
    from railride.studies.sweep import Case, run_cases
    from railride.studies.tuning import Objective

    opts = {"duration": 1.0}
    rows = run_cases(
        [
            Case("paper-sine", opts, suspension="pid", damper="ideal", gains={"pid.kp": 1e12, "pid.kd": 1e11}),
            Case("paper-sine", opts, suspension="pid", damper="ideal"),
        ]
    )
    assert rows["diverged_at_s"].iloc[0] > 0 and np.isnan(rows["diverged_at_s"].iloc[1])
    assert np.isnan(rows["acceleration_m_s2_rms"].iloc[0])
    assert np.isfinite(rows["acceleration_m_s2_rms"].iloc[1])
    # a tuner never picks it: a diverged run scores +inf under every objective
    for kind in ("sum", "minimax"):
        j = Objective(kind=kind).score(np.array([[np.nan] * 4, [5.0] * 4]))
        assert j[0] == np.inf and np.isfinite(j[1])
