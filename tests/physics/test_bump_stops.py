"""The secondary bump stops (`VehicleParams.z_stop`, `k_stop`; `railride.engine.laws.stop_force`):
against a second method (SciPy's adaptive integrator on the same equations), invariants (no
contact, no change; the lane stepper and the sample stepper agree), the exact discretisation
handing over to RK4 at contact, and step halving."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.integrate

import railride as rr
from railride.model.params import VehicleParams
from railride.model.vehicle import Vehicle
from railride.run.solver import SolverSettings

#: the paper's vehicle on bump stops at its (assumed) clearance, 80 mm, with a rubber stop's
#: order of stiffness; the paper preset itself only marks the clearance (k_stop = 0)
PAPER = VehicleParams.preset("paper").replace(k_stop=2.0e6)
N = 9


def _free_run(params, q0, dt=1e-4, duration=1.5, method="rk4"):
    sc = rr.scenario("bump", amplitude=1e-9, duration=duration)  # level track, in effect
    x0 = np.concatenate([q0, np.zeros(N)])
    return rr.simulate(sc, params, solver=SolverSettings(dt=dt, method=method, output_rate=500.0), initial_state=x0)


def _scipy_free_run(params, q0, times):
    """M q'' + C q' + K q = T f_stop(T^T q) by an adaptive Runge-Kutta method at tight tolerance."""
    v = Vehicle(params)
    minv = 1.0 / np.diag(v.M)
    z, k = params.z_stop, params.k_stop

    def stop(x):
        return np.where(x > z, -k * (x - z), np.where(x < -z, -k * (x + z), 0.0))

    def rhs(_t, y):
        q, qd = y[:N], y[N:]
        f = stop(v.T.T @ q)
        return np.concatenate([qd, minv * (-v.K @ q - v.C @ qd + v.T @ f)])

    sol = scipy.integrate.solve_ivp(
        rhs, (0.0, times[-1]), np.concatenate([q0, np.zeros(N)]), method="DOP853", t_eval=times, rtol=1e-11, atol=1e-13
    )
    return sol.y[:N].T


def test_a_carbody_released_beyond_its_stops_moves_as_scipy_integrates_it():
    # bounce and roll 30 mm past the 80 mm clearance at the corners: the stops act at once
    q0 = np.zeros(N)
    q0[0], q0[2] = 0.09, 0.02
    res = _free_run(PAPER, q0)
    q = res.dataset["carbody_bounce"].values
    ref = _scipy_free_run(PAPER, q0, res.dataset["time"].values)
    assert np.max(np.abs(q - ref[:, 0])) < 1e-6 * np.max(np.abs(ref[:, 0]))
    roll = res.dataset["carbody_roll"].values
    assert np.max(np.abs(roll - ref[:, 2])) < 1e-6 * np.max(np.abs(ref[:, 2]))
    # and the stops did act: without them the same start moves otherwise
    free = _free_run(PAPER.replace(z_stop=None, k_stop=0.0), q0).dataset["carbody_bounce"].values
    assert np.max(np.abs(free - q)) > 1e-3


def test_a_run_that_stays_off_the_stops_is_the_run_without_them():
    sc = rr.scenario("paper-sine", duration=2.0)
    none = PAPER.replace(z_stop=None, k_stop=0.0)
    assert VehicleParams.preset("paper").k_stop == 0.0  # the paper's preset: a marked clearance only
    for suspension in (None, rr.Suspension.named("sas-attitude-ride"), rr.Suspension.named("passive-on")):
        a = rr.simulate(sc, PAPER, suspension, solver=SolverSettings(method="rk4"))
        b = rr.simulate(sc, none, suspension, solver=SolverSettings(method="rk4"))
        assert np.max(np.abs(a.dataset["secondary_deflection"].values)) < PAPER.z_stop
        for name in ("carbody_bounce", "carbody_roll", "secondary_damper_force"):
            np.testing.assert_array_equal(a.dataset[name].values, b.dataset[name].values)


def test_the_stops_bound_the_travel_of_a_damper_that_gives_none():
    # passive-off (MR dampers at 0 V) on the paper's sine travels 0.5 m without stops
    sc = rr.scenario("paper-sine", duration=6.0)
    off = rr.Suspension.named("passive-off")
    free = rr.simulate(sc, PAPER.replace(z_stop=None, k_stop=0.0), off)
    stopped = rr.simulate(sc, PAPER, off)
    stiff = rr.simulate(sc, PAPER.replace(k_stop=5e7), off)
    travel = {
        name: float(np.max(np.abs(r.dataset["secondary_deflection"].values)))
        for name, r in (("free", free), ("stopped", stopped), ("stiff", stiff))
    }
    assert travel["free"] > 0.3
    assert PAPER.z_stop < travel["stopped"] < travel["free"] / 2
    # a stiffer stop: the travel beyond the clearance shrinks about as 1 / sqrt(k) for the
    # same energy (25 times stiffer: about 5 times less overtravel)
    over = {n: travel[n] - PAPER.z_stop for n in ("stopped", "stiff")}
    assert 2.5 < over["stopped"] / over["stiff"] < 10.0


def test_the_lane_stepper_and_the_sample_stepper_agree_at_the_stops(monkeypatch):
    from railride.engine import lanes

    sc = [rr.scenario("paper-sine", duration=3.0, amplitude=a) for a in np.linspace(0.05, 0.12, lanes.LANES)]
    suspension = rr.Suspension.named("skyhook")
    by_lanes = rr.simulate(sc, PAPER, suspension).dataset
    monkeypatch.setattr(lanes, "lanes_fit", lambda *a: False)
    by_samples = rr.simulate(sc, PAPER, suspension).dataset
    unmarked = rr.simulate(sc, PAPER.replace(k_stop=0.0), suspension).dataset  # the stops did act
    assert np.max(np.abs(unmarked["carbody_bounce"].values - by_samples["carbody_bounce"].values)) > 1e-4
    assert np.max(np.abs(by_lanes["secondary_deflection"].values)) > PAPER.z_stop  # some lanes touch
    for name in ("carbody_bounce", "carbody_roll", "secondary_damper_force"):  # to rounding (vector sums)
        a, b = by_lanes[name].values, by_samples[name].values
        assert np.max(np.abs(a - b)) < 1e-11 * np.max(np.abs(b))


def test_passive_runs_exact_off_the_stops_and_by_rk4_once_it_reaches_them():
    small = rr.simulate(rr.scenario("bump", amplitude=0.02, duration=2.0), PAPER)
    assert "exact" in small.dataset.attrs["integrator"]
    big_sc = rr.scenario("bump", amplitude=0.25, duration=2.0)
    big = rr.simulate(big_sc, PAPER)
    assert "Runge-Kutta" in big.dataset.attrs["integrator"] or "RK4" in big.dataset.attrs["integrator"]
    rk4 = rr.simulate(big_sc, PAPER, solver=SolverSettings(method="rk4"))
    np.testing.assert_array_equal(big.dataset["carbody_bounce"].values, rk4.dataset["carbody_bounce"].values)
    with pytest.raises(ValueError, match="bump stops"):
        rr.simulate(big_sc, PAPER, solver=SolverSettings(method="exact"))


def test_step_halving_converges_through_the_contacts():
    # the stop force has a kink at the clearance, and where it falls within a step varies with
    # dt: the error against the SciPy reference falls unevenly (measured 2.9e-8, 1.0e-8,
    # 9.4e-9, 5.0e-10 m at dt = 1, 0.5, 0.25, 0.125 ms), so over three halvings, at least as a
    # first-order method would (a factor 8)
    q0 = np.zeros(N)
    q0[0] = 0.1
    runs = {dt: _free_run(PAPER, q0, dt=dt, duration=1.0) for dt in (1e-3, 1.25e-4)}
    ref = _scipy_free_run(PAPER, q0, runs[1e-3].dataset["time"].values)[:, 0]
    err = {dt: np.max(np.abs(r.dataset["carbody_bounce"].values - ref)) for dt, r in runs.items()}
    assert err[1.25e-4] < err[1e-3] / 8
