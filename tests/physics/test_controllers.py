"""The semi-active laws against their definitions: skyhook's modal damping, the LQR's Riccati
equation and stability, the on-off and clipped voltage laws sample by sample, and the
constant-voltage baselines around the passive dampers."""

import numpy as np
import pytest
import scipy.linalg

from railride import dampers
from railride.studies.comparison import compare
from railride.secondary.control import OUTER_LOOPS, GainSet
from railride.secondary.controllers import ClippedOptimal, Skyhook
from railride.model.params import VehicleParams
from railride.run.simulation import simulate
from railride.run.solver import SolverSettings
from railride.secondary.suspension import Suspension
from railride.model.track import scenario
from railride.model.vehicle import Vehicle

P = VehicleParams.preset("paper")
V = Vehicle(P)
FLAT = scenario("paper-sine", amplitude=0.0, duration=8.0)


def _closed_loop_matrix(extra_damping: np.ndarray) -> np.ndarray:
    """x' = A x of M q'' + (C0 + extra) q' + K q = 0: the vehicle with the MR dampers' places
    empty and a linear force law written as a damping matrix."""
    minv = np.linalg.inv(V.M)
    A = np.zeros((18, 18))
    A[:9, 9:] = np.eye(9)
    A[9:, :9] = -minv @ V.K
    A[9:, 9:] = -minv @ (V.C0 + extra_damping)
    return A


def _carbody_bounce_mode(A: np.ndarray) -> complex:
    """The eigenvalue (Im > 0) whose mode holds most of its kinetic energy in carbody bounce."""
    lam, vec = np.linalg.eig(A)
    mass = np.diag(V.M)

    def bounce_share(i):
        energy = mass * np.abs(vec[:9, i]) ** 2
        return energy[0] / energy.sum()

    return complex(lam[max((i for i in range(lam.size) if lam[i].imag > 0), key=bounce_share)])


def _peaks(t: np.ndarray, z: np.ndarray, after: float) -> np.ndarray:
    """(value, time) of each maximum of z after ``after``, refined by a parabola through the
    three samples around it."""
    k = np.where((z[1:-1] > z[:-2]) & (z[1:-1] >= z[2:]))[0] + 1
    k = k[t[k] > after]
    a, b, c = z[k - 1], z[k], z[k + 1]
    shift = 0.5 * (a - c) / (a - 2 * b + c)
    return np.column_stack([b - 0.25 * (a - c) * shift, t[k] + shift * (t[1] - t[0])])


# -- skyhook -------------------------------------------------------------------------------------
def test_skyhook_on_the_ideal_actuator_adds_exactly_the_modal_damping_it_names():
    """A free decay in carbody heave (the carbody lifted 20 mm, rails flat) under the skyhook on
    the ideal actuator. By its definition the law puts -c_z z_c', -c_phi phi_c', -c_theta
    theta_c' on the carbody through the corners, f = T_c^+ Q_d, whose reactions load the
    bogies: the closed loop is the linear vehicle M q'' + (C0 + C_sky) q' + K q = 0 with
    C_sky[:, :3] = T T_c^+ diag(c) (T_c^+ here numpy's pseudo-inverse of the carbody rows of
    T). The log decrement and the damped period of the simulated z_c (successive maxima after
    the bogie modes have died out) equal those of that model's carbody bounce mode.

    Tolerance 1e-3 (relative): the controller runs at 1/dt, and the demand, held one period,
    lags the law by 1.5 dt on average, which shifts the 0.85 Hz mode by the order of
    c_z 1.5 dt / m_c = 1.5e-4 (7e-5 seen); the parabolic peak refinement at 10 kHz is good to
    ~1e-7."""
    c = 4e4  # a light skyhook: about 0.09 of critical in heave, so the decay shows many cycles
    law = Skyhook(c_z=c, c_phi=c * P.l**2, c_theta=c * P.d_s**2)
    x0 = np.zeros(18)
    x0[0] = 0.02
    dt = 1e-4
    ds = simulate(
        FLAT,
        P,
        Suspension.ideal(law),
        solver=SolverSettings(dt=dt, output_rate=10000.0, control_rate=1.0 / dt),
        initial_state=x0,
    ).dataset
    peaks = _peaks(ds.time.values, ds.carbody_bounce.values, after=1.5)
    assert len(peaks) >= 4
    decrement = np.log(peaks[:-1, 0] / peaks[1:, 0])
    period = np.diff(peaks[:, 1])

    C_sky = np.zeros((9, 9))
    C_sky[:, :3] = V.T @ np.linalg.pinv(V.T[:3]) @ np.diag([law.c_z, law.c_phi, law.c_theta])
    lam = _carbody_bounce_mode(_closed_loop_matrix(C_sky))
    expected_decrement = 2 * np.pi * -lam.real / lam.imag
    assert decrement == pytest.approx(np.full(decrement.size, expected_decrement), rel=1e-3)
    assert period == pytest.approx(np.full(period.size, 2 * np.pi / lam.imag), rel=1e-3)
    # and that damping is the skyhook's: the vehicle without it decays far more slowly
    bare = _carbody_bounce_mode(_closed_loop_matrix(np.zeros((9, 9))))
    assert 2 * np.pi * -bare.real / bare.imag < 0.2 * expected_decrement


def test_skyhook_puts_exactly_its_modal_forces_on_the_carbody():
    law = Skyhook(c_z=3e5, c_phi=2e7, c_theta=4e5)
    G, H = law.gains(V)
    rates = np.array([0.1, -0.02, 0.03])
    f = G @ np.concatenate([[0.05, 0.01, -0.02], rates])  # displacements do not enter
    Q = V.T[:3] @ f  # heave force, pitch and roll moments on the carbody
    assert Q == pytest.approx(-np.array([law.c_z, law.c_phi, law.c_theta]) * rates, rel=1e-12)
    assert np.all(H == 0)


# -- clipped-optimal: the LQR -------------------------------------------------------------------
def _design_model(law: ClippedOptimal):
    """The design model from the vehicle's matrices, assembled here: the secondary vertical
    dampers c_sz taken out of C, the four corner forces the input, the carbody weighted."""
    C_without = V.C - P.c_sz * V.T @ V.T.T
    minv = np.linalg.inv(V.M)
    A = np.block([[np.zeros((9, 9)), np.eye(9)], [-minv @ V.K, -minv @ C_without]])
    B = np.vstack([np.zeros((9, 4)), minv @ V.T])
    q = np.zeros(18)
    q[[0, 1, 2, 9, 10, 11]] = law.q_z, law.q_phi, law.q_theta, law.qd_z, law.qd_phi, law.qd_theta
    return A, B, np.diag(q), law.r * np.eye(4)


@pytest.mark.parametrize(
    "law",
    [GainSet.default().clipped_optimal, ClippedOptimal(1e10, 0.0, 3e11, 0.0, 5e12, 1e9, 0.5)],
    ids=["shipped", "other"],
)
def test_lqr_gain_solves_the_riccati_equation_and_stabilises_the_design_model(law):
    A, B, Q, R = _design_model(law)
    K, P_ = law.lqr(V)
    G, H = law.gains(V)
    assert np.array_equal(G, -K) and np.all(H == 0)
    assert np.allclose(P_, P_.T, rtol=0, atol=1e-9 * np.abs(P_).max())
    # the CARE residual, small against the size of its terms
    terms = (A.T @ P_, P_ @ A, P_ @ B @ np.linalg.solve(R, B.T @ P_), Q)
    residual = sum(terms[:2]) - terms[2] + terms[3]
    assert np.abs(residual).max() < 1e-8 * max(np.abs(t).max() for t in terms)
    assert np.allclose(K, np.linalg.solve(R, B.T @ P_), rtol=1e-10, atol=1e-12 * np.abs(K).max())
    # the gain is the stabilising one, and the same as an independent solution gives
    assert np.linalg.eigvals(A - B @ K).real.max() < 0
    assert np.allclose(P_, scipy.linalg.solve_continuous_are(A, B, Q, R), rtol=1e-8, atol=1e-8 * np.abs(P_).max())


def test_lqr_closed_loop_on_the_ideal_actuator_is_stable():
    """A free decay (carbody lifted, pitched and rolled; rails flat) under the clipped-optimal
    law's demand on the ideal actuator dies away."""
    x0 = np.zeros(18)
    x0[:3] = 0.02, 0.002, 0.005
    res = simulate(FLAT, P, Suspension.ideal(GainSet.default().clipped_optimal), initial_state=x0, on_divergence="mark")
    assert not np.isfinite(res.diverged_at).any()
    ds = res.dataset
    q = np.column_stack([ds[n].values for n in ("carbody_bounce", "carbody_pitch", "carbody_roll")])
    assert np.all(np.abs(q[-1000:]).max(axis=0) < 0.02 * np.abs(x0[:3]))


# -- the voltage laws, sample by sample ------------------------------------------------------------
@pytest.fixture(scope="module")
def switched():
    """skyhook-on-off and clipped-optimal with the railway MR dampers on paper-sine, every
    integration step recorded."""
    g = GainSet.default()
    return simulate(
        scenario("paper-sine", duration=3.0),
        P,
        [Suspension.named(n, g) for n in ("skyhook-on-off", "clipped-optimal")],
        solver=SolverSettings(output_rate=10000.0),
    ).dataset


def _after_first_period(ds):
    return ds.isel(time=ds.time.values >= 1.0 / 1000.0 - 1e-12)  # the default controller rate


def test_on_off_skyhook_gives_v_max_exactly_where_the_demand_dissipates(switched):
    """At every sample after the first controller period: v = v_max where f_d x' < 0 (a force
    the damper gives while dissipating: its force on the carbody is -c x'), v_min elsewhere;
    x' the secondary deflection rate, carbody point minus bogie point, from the Dataset."""
    ds = _after_first_period(switched.isel(sample=0))
    v = ds.damper_command_voltage.values
    fd, rate = ds.damper_demand_force.values, ds.secondary_deflection_velocity.values
    d = dampers.RAILWAY
    dissipating = fd * rate < 0
    assert dissipating.any() and (~dissipating).any()
    assert np.all(v[dissipating] == d.v_max) and np.all(v[~dissipating] == d.v_min)
    # the demand is the skyhook's (the same outer loop, another voltage law): the demand held
    # from 0.5 s was computed from the carbody states sampled at 0.499 s
    G, _ = GainSet.default().skyhook_on_off.gains(V)  # the on-off law's own table
    run, t = switched.isel(sample=0), switched.time.values
    body = ("carbody_bounce", "carbody_pitch", "carbody_roll")
    m = np.array([float(run[n][np.isclose(t, 0.499)][0]) for n in (*body, *(f"{n}_velocity" for n in body))])
    assert run.damper_demand_force.values[np.isclose(t, 0.5)][0] == pytest.approx(G @ m, rel=1e-9)


def test_clipped_optimal_never_asks_the_damper_for_energy(switched):
    """Dyke et al. (1996): v = v_max where (f_d - f) f > 0, v_min elsewhere; wherever the
    damper is commanded to v_max the demand and the damper's force on the carbody have the same
    sign (the damper is asked for more of the force it already gives)."""
    ds = _after_first_period(switched.isel(sample=1))
    v = ds.damper_command_voltage.values
    fd, f = ds.damper_demand_force.values, ds.secondary_damper_force.values
    d = dampers.RAILWAY
    on = v == d.v_max
    assert on.any() and (v[~on] == d.v_min).all()
    assert np.all(np.sign(fd[on]) == np.sign(f[on])) and np.all(((fd - f) * f)[on] > 0)
    assert np.all(((fd - f) * f)[~on] <= 0)


# -- passive-on and passive-off ------------------------------------------------------------------------
def test_passive_on_and_off_bracket_the_viscous_passive_dampers():
    """The MR dampers held at v_min give less force than the passive dampers c_sz, held at v_max
    more (RMS over the run); their voltages are the range's ends; and they have no bound on the
    ideal devices (a constant voltage means nothing there), which the results say."""
    res = compare(scenario("paper-sine", duration=4.0), controllers=["passive-on", "passive-off"])
    assert res.names == ["passive", "passive-on", "passive-off"]
    demand = res.demands()
    force = {n: demand[n]["force_rms_n"] for n in res.names}
    assert force["passive-off"] < force["passive"] < force["passive-on"]
    assert demand["passive-on"]["voltage_at_max_fraction"] == 1.0
    assert demand["passive-off"]["voltage_mean_v"] == dampers.RAILWAY.v_min
    doc = res.to_dict()
    assert doc["bounds"] is None  # no outer loop: nothing to run on the ideal devices
    assert [r["paper"] for r in doc["controllers"][1:]] == [None, None]
    assert doc["gains"]["passive-on"] is None


def test_passive_on_has_no_bound_beside_a_controller_and_no_run_on_the_ideal_devices():
    sc = scenario("paper-sine", duration=1.0)
    doc = compare(sc, controllers=["skyhook", "passive-on"]).to_dict()
    for device in ("ideal", "ideal-damper"):
        assert doc["bounds"][device]["passive-on"]["rms"]["roll_deg"] is None
        assert "no meaning on the ideal devices" in doc["bounds"][device]["passive-on"]["note"]
        assert doc["bounds"][device]["skyhook"]["rms"]["roll_deg"] > 0
    ideal = compare(sc, controllers=["all"], damper="ideal", gains=GainSet.reference())
    assert ideal.names == ["passive", *OUTER_LOOPS]  # passive-on and passive-off said, not run
    assert set(ideal.settings["not_run"]) == {"passive-on", "passive-off"}
    assert "no voltage" in ideal.to_dict()["settings"]["not_run"]["passive-on"]


def test_a_law_that_diverges_on_a_device_is_said_and_the_others_go_on():
    # the shipped groundhook gain (tuned for the MR dampers, which saturate) is far too stiff for
    # the ideal actuator at dt = 1e-4 s: that run stops; the comparison of the others goes on
    sc = scenario("paper-sine", duration=1.0)
    gains = GainSet.reference().apply({"groundhook.c_g": 1e8})
    cmp = compare(sc, controllers=["pid", "groundhook"], damper="ideal", gains=gains)
    assert cmp.names == ["passive", "pid"]
    why = cmp.to_dict()["settings"]["not_run"]["groundhook"]
    assert why.startswith("diverged at t = ") and "'ideal'" in why and "dt = 0.0001 s" in why
    with_mr = compare(sc, controllers=["groundhook"], gains=gains)  # the MR run is fine; its bound is marked
    assert with_mr.names == ["passive", "groundhook"]
    assert with_mr.bounds_record()["ideal"]["groundhook"]["diverged_at_s"] > 0
