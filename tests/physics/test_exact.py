"""The exact discretisation of the passive vehicle (railride.engine.discrete) against the RK4 stepper,
against itself at half the step, and against the frequency-domain steady state."""

from __future__ import annotations

import numpy as np
import pytest

import railride as rr
from railride.model.vehicle import Vehicle

RK4 = rr.SolverSettings(method="rk4")
CHANNELS = ("carbody_bounce", "carbody_pitch", "carbody_roll", "carbody_acceleration", "front_bogie_bounce")


def _worst(a: rr.RideResult, b: rr.RideResult, channels=CHANNELS) -> float:
    """The largest difference over the channels, relative to each channel's largest value."""
    worst = 0.0
    for name in channels:
        x, y = a.dataset[name].values, b.dataset[name].values
        worst = max(worst, float(np.max(np.abs(x - y)) / np.max(np.abs(y))))
    return worst


@pytest.mark.parametrize("name, options", [("paper-sine", {}), ("bump", {}), ("fra4", {"seed": 4})])
def test_exact_agrees_with_rk4(name, options):
    """RK4 at dt = 1e-4 s is accurate to about 1e-9 of the response on these tracks: the two
    methods agree to 1e-7."""
    scenario = rr.scenario(name, duration=6.0, **options)
    exact, rk4 = rr.simulate(scenario), rr.simulate(scenario, solver=RK4)
    assert exact.dataset.attrs["integrator"].startswith("exact discretisation")
    assert rk4.dataset.attrs["integrator"].startswith("classical RK4")
    channels = CHANNELS if name != "bump" else CHANNELS[:2] + CHANNELS[3:]  # no roll on a level bump
    assert _worst(exact, rk4, channels) < 1e-7


def test_rk4_error_shrinks_towards_the_exact_result():
    """RK4 converges at fourth order towards the exact result: halving dt from 4e-4 s divides
    its error by 16 (measured 16.1, and 16.1 again from 2e-4 to 1e-4 s; same input grid)."""
    scenario = rr.scenario("fra4", duration=4.0, seed=1, min_wavelength=2.0)
    exact = rr.simulate(scenario, solver=rr.SolverSettings(dt=4e-4, output_rate=500.0))
    errors = [
        _worst(rr.simulate(scenario, solver=rr.SolverSettings(dt=dt, output_rate=500.0, method="rk4")), exact)
        for dt in (4e-4, 2e-4)
    ]
    assert 8.0 < errors[0] / errors[1] < 32.0  # 16 for fourth order


def test_exact_does_not_depend_on_the_step():
    """dt only places the input grid: with the same grid (paper-sine's nodes are 3 m apart)
    dt = 1e-4 and 5e-5 s give the same histories to rounding."""
    scenario = rr.scenario("paper-sine", duration=3.0)
    a = rr.simulate(scenario, solver=rr.SolverSettings(dt=1e-4))
    b = rr.simulate(scenario, solver=rr.SolverSettings(dt=5e-5))
    assert _worst(a, b) < 1e-12


def test_exact_reaches_the_frequency_domain_steady_state():
    """On the tapered sine, once the start has died away (after 15 s), every response is the
    frequency response to z_L = A sin(wt), z_R = A sin(wt - psi) at f = V / wavelength."""
    scenario = rr.scenario("paper-sine", duration=20.0)
    track = scenario.track
    f = scenario.speed / track.wavelength
    psi = np.deg2rad(track.rail_phase_deg)
    H = Vehicle().frequency_response([f], scenario.speed, rails=(1.0, np.exp(-1j * psi)))
    ds = rr.simulate(scenario).dataset
    late = ds["time"].values >= 15.0
    t = ds["time"].values[late]
    for name in ("carbody_bounce", "carbody_pitch", "carbody_roll", "front_bogie_roll"):
        h = complex(H[name].values[0])
        expected = track.amplitude * np.abs(h) * np.sin(2 * np.pi * f * t + np.angle(h))
        got = ds[name].values[late]
        assert np.max(np.abs(got - expected)) < 1e-6 * np.max(np.abs(expected)), name


def test_exact_is_refused_where_the_vehicle_is_not_linear():
    with pytest.raises(ValueError, match="method = 'exact': applies where the vehicle is linear only"):
        rr.simulate("paper-sine", suspension=rr.Suspension.named("mr"), solver=rr.SolverSettings(method="exact"))
    with pytest.raises(ValueError, match="method = 'euler'"):
        rr.SolverSettings(method="euler")


@pytest.mark.parametrize("name", ["pid", "sas-attitude-ride", "skyhook", "clipped-optimal"])
def test_exact_closed_loop_on_the_ideal_actuator_agrees_with_rk4(name):
    """An outer loop on the ideal actuator is linear too (the held demand is the force): the
    exact steps split at rail nodes, controller samples and outputs, and agree with the RK4
    stepper's closed loop to its error (below 1e-8 of each response)."""
    suspension = rr.Suspension.named(name, damper="ideal")
    scenario = rr.scenario("fra4", duration=4.0, seed=2)
    exact, rk4 = rr.simulate(scenario, suspension=suspension), rr.simulate(scenario, suspension=suspension, solver=RK4)
    assert exact.dataset.attrs["integrator"].startswith("exact discretisation")
    assert _worst(exact, rk4, (*CHANNELS, "damper_demand_force", "secondary_damper_force")) < 1e-8


@pytest.mark.parametrize("delay, rate", [(3, 1000.0), (1, 500.0), (2, 2000.0)])
def test_exact_closed_loop_keeps_the_controller_timing(delay, rate):
    """Delays and controller rates other than the output rate: the same sampled loop as RK4's."""
    suspension = rr.Suspension.named("sas-attitude", damper="ideal").with_delay(delay)
    scenario = rr.scenario("paper-sine", duration=3.0)
    exact = rr.simulate(scenario, suspension=suspension, solver=rr.SolverSettings(control_rate=rate))
    rk4 = rr.simulate(scenario, suspension=suspension, solver=rr.SolverSettings(control_rate=rate, method="rk4"))
    assert _worst(exact, rk4) < 1e-10


def test_exact_closed_loop_diverges_where_rk4_does():
    """The shipped groundhook gain is unstable on the ideal actuator: marked at the same time."""
    names = ("pid", "groundhook", "sas-attitude")
    suspensions = [rr.Suspension.named(n, damper="ideal") for n in names]
    scenario = rr.scenario("paper-sine", duration=2.0)
    exact = rr.simulate(scenario, suspension=suspensions, on_divergence="mark")
    rk4 = rr.simulate(scenario, suspension=suspensions, on_divergence="mark", solver=RK4)
    assert np.isnan(exact.diverged_at[[0, 2]]).all()
    assert exact.diverged_at[1] == pytest.approx(rk4.diverged_at[1])


def test_nonlinear_or_noisy_loops_stay_with_rk4():
    scenario = rr.scenario("paper-sine", duration=1.0)
    dissipative = rr.simulate(scenario, suspension=rr.Suspension.named("pid", damper="ideal-damper"))
    assert dissipative.dataset.attrs["integrator"].startswith("classical RK4")
    with pytest.raises(ValueError, match="ideal semi-active damper"):
        rr.simulate(
            scenario,
            suspension=rr.Suspension.named("pid", damper="ideal-damper"),
            solver=rr.SolverSettings(method="exact"),
        )
