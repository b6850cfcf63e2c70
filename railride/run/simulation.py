"""The one entry point: `simulate` runs one scenario or a batch and returns a `RideResult`."""

from __future__ import annotations

import functools
import math
import time
from datetime import datetime, timezone

import numpy as np

from railride.secondary import dampers
from railride.engine import kernels, layout
from railride.engine import lanes
from railride import limits
from railride.defaults import DEFAULT_DT
from railride.errors import DivergenceError, InputError, Interrupted
from railride.secondary.faults import fault_table
from railride.secondary.sensing import reads_bogies
from railride.model.params import VehicleParams
from railride.run.solver import SolverSettings, check_resolution
from railride.secondary.suspension import Suspension, batch_conflict
from railride.model.track import Scenario, input_table_nodes, table_key
from railride.model.track import as_scenario
from railride.validation import shown
from railride.run.inputs import (  # noqa: F401  (the stores, read here by tests and benchmarks)
    _FORCING_TABLES,
    _INPUT_TABLES,
    _forcing,
    _input_table,
    _system_arrays,
    _vehicle,
)
from railride.run.ride import RideResult, build_dataset, has_damper_states
from railride.model.vehicle import N_DOF, Vehicle

#: sample-steps of the first kernel call when a progress callback is given; later calls are
#: sized to take about _CHUNK_SECONDS each, so that the callback, and Ctrl-C, which Python sees
#: only between calls, come a few times a second whatever the damper law costs per step
_CHUNK_WORK = 20_000
_CHUNK_SECONDS = 0.25


def _rk4_gain(z: np.ndarray) -> np.ndarray:
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


@functools.lru_cache(maxsize=256)
def _max_stable_dt(params: VehicleParams, damper=None) -> float:
    return max_stable_dt(_vehicle(params), damper)


def _state_matrix(vehicle: Vehicle, damper=None) -> np.ndarray:
    """The passive state matrix, or with MR dampers the vehicle linearised about their stiffest
    state: pre-yield stiffness k0 + k1 + alpha(v_max) A and damping c0(v_max) + c1(v_max). Their
    internal states are sub-stepped by the stepper and do not enter here."""
    if damper is None:
        return vehicle.state_matrix
    if damper.law == dampers.LAW_IDEAL:
        # its force is the held demand, a forcing term to the integrator: C0 without a damper
        k_eff, c_eff = 0.0, 0.0
    elif damper.law == dampers.LAW_VISCOUS:
        k_eff, c_eff = 0.0, damper.c
    else:
        v = damper.v_max
        k_eff = damper.k0 + getattr(damper, "k1", 0.0) + (damper.alpha_a + damper.alpha_b * v) * damper.A
        c_eff = damper.c0a + damper.c0b * v + getattr(damper, "c1a", 0.0) + getattr(damper, "c1b", 0.0) * v
    TT = vehicle.T @ vehicle.T.T
    K = vehicle.K + k_eff * TT
    C = vehicle.C0 + c_eff * TT
    minv = 1.0 / np.diag(vehicle.M)[:, None]
    A = np.zeros((2 * N_DOF, 2 * N_DOF))
    A[:N_DOF, N_DOF:] = np.eye(N_DOF)
    A[N_DOF:, :N_DOF] = -minv * K
    A[N_DOF:, N_DOF:] = -minv * C
    return A


def max_stable_dt(vehicle: Vehicle, damper=None) -> float:
    """Largest RK4 step for which every mode of the vehicle is stable (with MR dampers: of the
    vehicle linearised about the dampers' stiffest state)."""
    lam = np.linalg.eigvals(_state_matrix(vehicle, damper))
    lo, hi = 0.0, 10.0
    for _ in range(60):  # bisection on |R(lambda dt)| <= 1
        mid = 0.5 * (lo + hi)
        if np.all(_rk4_gain(lam * mid) <= 1.0 + 1e-12):
            lo = mid
        else:
            hi = mid
    return lo


#: the most output-step phases (distinct step maps) the exact discretisation builds: the default
#: grids need one; a dt that splits the output interval and the input nodes unevenly needs up to
#: the node spacing in steps (330 000 at dt = 3e-9 s: minutes of matrix exponentials)
_MAX_EXACT_PHASES = 1000

#: what a result's ``integrator`` attribute says of each method
INTEGRATOR_RK4 = "classical RK4, fixed step"
INTEGRATOR_EXACT = "exact discretisation (matrix exponential, one step per output sample; railride.discrete)"


def _exact(solver, damper, closed, suspensions, n_vehicles: int = 1) -> bool:
    """Whether the run takes the exact discretisation: method "exact", or "auto" where the
    vehicle is linear: the passive viscous dampers, or an outer loop on the ideal actuator with
    exact states (no sensing, no sensor noise); "exact" with anything else is refused. "auto"
    keeps RK4 for a batch of several vehicles that fills the lane stepper: each vehicle costs a
    matrix exponential, which costs more than its whole RK4 run there (a 64-vehicle passive
    batch of 2 s: 0.26 s exact, 0.10 s RK4; benchmarks/bench_passive.py)."""
    faults = any(s.faults for s in suspensions)
    passive = damper is None and closed is None
    actuator = (
        closed is not None
        and damper is not None
        and damper.law == dampers.LAW_IDEAL
        and not damper.dissipative
        and closed["sensing"] is None
        and len(closed["noise"]) == 0
    )
    linear = (passive or actuator) and not faults
    if solver.method == "exact" and not linear:
        raise InputError(
            "method = 'exact': applies where the vehicle is linear only: the passive viscous "
            "suspension, or an outer loop on the ideal actuator with exact states; MR dampers, the "
            "ideal semi-active damper, sensing, sensor noise and faults run with method 'rk4' or 'auto'"
        )
    if solver.method == "auto" and n_vehicles > 1 and len(suspensions) >= lanes.LANES:
        return False
    return linear and solver.method != "rk4"


def _check_dt(vehicle: Vehicle, dt: float, damper=None) -> None:
    with np.errstate(all="ignore"):  # a vehicle beyond double precision is reported below
        dt_max = _max_stable_dt(vehicle.params, damper)
    if dt > dt_max:
        from railride.model.modes import checked_modes

        # the vehicle's modes, or the error that says why they cannot be computed
        fastest = max(checked_modes(vehicle), key=lambda m: m.frequency_hz)
        stiffer = "" if not has_damper_states(damper) else f", stiffer with the {damper.model} dampers"
        why = f"(fastest mode {fastest.label}, {shown(fastest.frequency_hz)} Hz{stiffer})"
        if not dt_max > 0.0:  # the bisection found no stable step: eigenvalues past what it can resolve
            raise InputError(
                f"dt = {shown(dt)} s: no step keeps fourth-order Runge-Kutta stable for this vehicle {why}; "
                "check its masses and stiffnesses"
            )
        default = f" (the default {DEFAULT_DT:g} s is accurate)" if DEFAULT_DT <= dt_max else ""
        raise InputError(
            f"dt = {shown(dt)} s is too large: fourth-order Runge-Kutta is unstable for this vehicle {why}; "
            f"use dt <= {shown(dt_max)} s{default}"
        )


def _check_size(scenarios, solver: SolverSettings, damper, closed, exact: bool, n_out: int, duration: float):
    """`railride.limits.check` on what a run allocates before it allocates it: the stored
    histories (samples x output rows x channels), the rail input and forcing tables, and the
    exact stepper's maps (one per phase of the output steps against the table's nodes)."""
    n, dt, stride = len(scenarios), solver.dt, solver.output_steps
    limits.check_steps("dt", n_out * stride, "raise dt or shorten the run")
    channels = 3 * N_DOF + 4 + 16 + (layout.N_DS if has_damper_states(damper) else 0) + (8 if closed else 0)
    need = 8.0 * n * (n_out + 1) * channels
    nodes, interval = max(input_table_nodes(sc, dt, duration) for sc in scenarios)
    need += 8.0 * n * nodes * (16 + 36)  # input and forcing tables, at most one each per sample
    if exact:  # discrete.ExactStepper: period x 18 x (span x 8)
        m = int(round(interval / dt))
        period, span = math.lcm(stride, m) // stride, (stride + m - 1) // m + 2
        need += 8.0 * period * 2 * N_DOF * span * 8
    limits.check(
        need,
        f"{n} run(s) of {duration:.4g} s at dt {dt:.4g} s ({n_out + 1} output samples, {nodes} input nodes)",
        "shorten the duration, lower output_rate, run fewer samples at once or use a dt nearer the default",
    )
    if exact and period > _MAX_EXACT_PHASES:  # each phase costs matrix exponentials, 1-2 ms each
        raise InputError(
            f"dt = {shown(dt)} s: the exact discretisation would build {period} step maps (the output "
            f"interval, {stride} steps, and the input table's node spacing, {m} steps, line up again "
            f"only every {period} output samples); use a dt that divides both evenly, such as the "
            f"default {DEFAULT_DT:g} s (or, from Python, SolverSettings(method='rk4'))"
        )
    # time, which memory does not bound (the histories are strided): the exact method steps
    # once per output sample (and controller sample), RK4 once per dt
    if exact:
        steps = n_out * stride // (stride if closed is None else math.gcd(stride, closed["stride"]))
        shrink = "shorten the duration, lower output_rate or run fewer samples at once"
    else:
        steps = n_out * stride
        shrink = f"raise dt (the default is {DEFAULT_DT:g} s), shorten the duration or run fewer samples at once"
    runs = "1 run" if n == 1 else f"{n} runs"
    limits.check_work(n, steps, f"{runs} of {duration:.4g} s at dt {dt:.4g} s", shrink)


def _as_list(x):
    if x is None or isinstance(x, (Scenario, VehicleParams, str)) or not hasattr(x, "__iter__"):
        return [x]
    return list(x)


def _full_state_gains(G, controller) -> np.ndarray:
    """The outer loop's G as a map from the whole state (q, q') (4 x 18): a law on the carbody
    states alone gives G over (z_c, phi_c, theta_c, z_c', phi_c', theta_c') (4 x 6)."""
    G = np.asarray(G, dtype=float)
    if G.shape == (4, 2 * N_DOF):
        return G
    if G.shape != (4, 6):
        raise InputError(
            f"controller {getattr(controller, 'name', controller)!r}: gains(vehicle) gave G of shape {G.shape}; "
            f"allowed (4, 6) on the carbody states or (4, {2 * N_DOF}) on (q, q')"
        )
    full = np.zeros((4, 2 * N_DOF))
    full[:, :3], full[:, N_DOF : N_DOF + 3] = G[:, :3], G[:, 3:]
    return full


def _as_suspensions(suspension) -> list[Suspension]:
    items = list(suspension) if isinstance(suspension, (list, tuple)) else [suspension]
    items = [Suspension() if s is None else s for s in items]
    for s in items:
        if not isinstance(s, Suspension):
            raise InputError(f"suspension = {s!r}: must be a railride.Suspension, a list of them, or None (passive)")
    return items


def _command_voltage(s: Suspension) -> float:
    """The command a sample's coils start at (and hold, in open loop): the set voltage, v_min
    under a closed loop; 0 where there is no coil."""
    if s.voltage is not None:
        return s.voltage
    return s.damper.v_min if has_damper_states(s.damper) else 0.0


def _closed_loop(suspensions: list[Suspension], solver: SolverSettings, duration: float):
    """The closed-loop settings the stepper needs (every sample's outer loop, the shared inner
    loop and sensor noise); None for an open loop."""
    first = suspensions[0]
    if not first.closed_loop:
        return None
    stride = solver.control_steps(duration)
    ticks = int(round(duration / (stride * solver.dt))) + 2
    limits.check(ticks * 10 * 8.0, f"the sensor noise of {ticks:.4g} controller samples", "lower control_rate")
    noise = first.sensor_noise
    sensing = first.sensing
    if sensing is not None:
        sensing.check(solver.control_rate, solver.dt)
    return {
        "controllers": [s.controller for s in suspensions],
        "inner": first.inner,
        "rate": solver.control_rate,
        "stride": stride,
        "noise": noise.samples(ticks) if noise is not None else np.zeros((0, 6)),
        "sensor_noise": noise,
        "sensing": sensing,
        "snoise": sensing.samples(ticks) if sensing is not None else np.zeros((0, 4)),
    }


def simulate(
    scenario=None,
    params=None,
    suspension=None,
    *,
    solver=None,
    initial_state=None,
    progress=None,
    on_divergence: str = "raise",
) -> "RideResult":
    """Simulate the vehicle on one or many scenarios.

    ``scenario`` is a `Scenario`, a scenario name (see `railride.model.track.scenario`) or a list of
    them; ``params`` is a `VehicleParams`, a preset name or a list; ``suspension`` a
    `railride.Suspension` (None: passive, the viscous dampers c_sz) or a list. Lists run as one
    batch along a ``sample`` dimension (a single item is broadcast against a list). Every
    sample of a batch must share the duration, and the suspensions of a batch one damper model,
    inner loop and sensor noise (`railride.secondary.suspension.batch_conflict`): a batch varies the
    constant voltages or the outer loops. MR dampers start with their coils at the command
    (v_min under a closed loop) and their hysteretic states at 0. A closed loop samples the
    carbody states at the solver's control rate.
    ``solver`` (`railride.SolverSettings`, default: its defaults) holds the fixed RK4 step dt
    [s], the output rate [Hz] of the stored time histories and the controllers' rate [Hz].
    ``initial_state`` is (q, q') at t = 0 as 18 numbers in DOF order (m, rad, m/s, rad/s), or
    one row per sample; by default the vehicle starts at rest in equilibrium.
    ``progress(done_fraction)`` is called between chunks of a long run.
    A sample whose response leaves +-1000 (m or rad) or stops being finite has diverged: with
    ``on_divergence="raise"`` (the default) the run stops with a `railride.errors.DivergenceError`
    (a RuntimeError) giving the sample and the time; with ``"mark"`` (what studies use) the
    other samples stand, the diverged one's histories are NaN from that time on, and
    `RideResult.diverged_at` gives the time.
    """
    solver = SolverSettings.of(solver)
    dt, output_rate = solver.dt, solver.output_rate
    if on_divergence not in ("raise", "mark"):
        raise InputError(
            f"on_divergence = {on_divergence!r}: allowed 'raise' (stop with an error) "
            "or 'mark' (keep the other samples; see RideResult.diverged_at)"
        )
    batch = (
        not (isinstance(scenario, (Scenario, str)) or scenario is None)
        or not (isinstance(params, (VehicleParams, str)) or params is None)
        or isinstance(suspension, (list, tuple))
    )
    scenarios = [as_scenario(s) for s in _as_list(scenario)]
    param_sets = [VehicleParams.of(p) for p in _as_list(params)]
    suspensions = _as_suspensions(suspension)
    counts = (len(scenarios), len(param_sets), len(suspensions))
    n = max(counts)
    if any(k not in (1, n) for k in counts):
        raise InputError(
            f"a batch needs equally many scenarios, parameter sets and suspensions, "
            f"or one of each; got {counts[0]} scenarios, {counts[1]} parameter sets "
            f"and {counts[2]} suspensions"
        )
    if n == 0:
        raise InputError("an empty batch: give at least one scenario")
    scenarios = scenarios * (n // len(scenarios))
    param_sets = param_sets * (n // len(param_sets))
    suspensions = suspensions * (n // len(suspensions))
    duration = scenarios[0].duration
    if any(abs(s.duration - duration) > 1e-12 * duration for s in scenarios):
        raise InputError(
            "every sample of a batch must have the same duration; got "
            + ", ".join(sorted({f"{s.duration:g} s" for s in scenarios}))
        )
    conflict = batch_conflict(suspensions)
    if conflict is not None:
        raise InputError(conflict)
    damper = suspensions[0].damper
    vcmd = np.array([[_command_voltage(s)] * 4 for s in suspensions], dtype=float)
    closed = _closed_loop(suspensions, solver, duration)
    exact = _exact(solver, damper, closed, suspensions, len(set(param_sets)))
    vehicles = {}
    for p in param_sets:
        if id(p) not in vehicles:
            vehicles[id(p)] = _vehicle(p)
            if not exact:  # the exact steps are stable at any dt
                _check_dt(vehicles[id(p)], dt, damper)
    stride = solver.output_steps
    n_out_f = duration * output_rate
    n_out = int(round(n_out_f))
    if abs(n_out - n_out_f) > 1e-6 * max(1.0, n_out_f) or n_out < 1:
        raise InputError(f"duration = {duration:g} s must be a whole number of output intervals (1/{output_rate:g} Hz)")
    n_steps = n_out * stride
    for sc in scenarios:  # the track's shortest wavelength must show in the output
        check_resolution(sc, output_rate)
    _check_size(scenarios, solver, damper, closed, exact, n_out, duration)

    systems = {key: _system_arrays(v, passive=damper is None) for key, v in vehicles.items()}
    arrays = {k: np.ascontiguousarray(np.stack([systems[id(p)][k] for p in param_sets])) for k in ("A", "TS", "c_sec")}

    # rail inputs depend on the scenario and the wheelset spacing, the forcing also on the
    # vehicle: tables are shared between the samples that agree on those
    utabs: list[np.ndarray] = []
    ftabs: list[np.ndarray] = []
    u_index: dict[tuple, tuple] = {}
    f_index: dict[tuple, int] = {}
    u_off, f_off, n_nodes, interval = (
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n),
    )
    keys: dict[int, object] = {}
    for i, (sc, p) in enumerate(zip(scenarios, param_sets)):
        lag = tuple(vehicles[id(p)].wheelset_lag_distance)
        if id(sc) not in keys:
            keys[id(sc)] = table_key(sc)
        skey = keys[id(sc)]
        # by value where the scenario has one: equal scenarios and vehicles given as separate
        # objects (a study's cases) share one table in the batch, not a copy each
        ukey = (id(sc) if skey is None else skey, lag)
        if ukey not in u_index:
            tab, itv = _input_table(sc, skey, lag, dt, duration)
            u_index[ukey] = (sum(len(t) for t in utabs), tab, itv)
            utabs.append(tab)
        u_off[i], tab, interval[i] = u_index[ukey]
        n_nodes[i] = len(tab)
        fkey = (ukey, p)
        if fkey not in f_index and not exact:  # the exact steps take the inputs themselves
            f_index[fkey] = sum(len(t) for t in ftabs)
            ftabs.append(_forcing(skey, lag, dt, duration, p, tab))
        f_off[i] = f_index.get(fkey, 0)
    utab = np.ascontiguousarray(np.concatenate(utabs))
    ftab = np.ascontiguousarray(np.concatenate(ftabs)) if ftabs else np.zeros((1, 36))

    rows = n_out + 1
    law = layout.LAW_VISCOUS_IN_C if damper is None else damper.law
    gm = np.zeros((n, 4, 2 * N_DOF))
    hm = np.zeros((n, 4, 3))
    modes = np.zeros(n)  # the voltage law of each sample (dampers.VOLTAGE_LAWS)
    sensing = np.zeros((n, layout.SENSING_COLS))
    snoise = np.zeros((0, 4))
    if closed is not None:
        for i, (c, p) in enumerate(zip(closed["controllers"], param_sets)):
            G, hm[i] = c.gains(vehicles[id(p)])
            gm[i] = _full_state_gains(G, c)
            modes[i] = dampers.VOLTAGE_LAWS.index(getattr(c, "voltage_law", "tracking"))
            if closed["sensing"] is not None:
                if reads_bogies(gm[i]):
                    raise InputError(
                        f"sensing with controller {c.name!r}: it reads the bogies' states, and the "
                        "accelerometers are on the carbody only (railride.secondary.sensing)"
                    )
                sensing[i] = closed["sensing"].pack(vehicles[id(p)].T[:3])
        snoise = closed["snoise"]
    x = np.zeros((n, layout.NX))
    x[:, 2 * N_DOF + 2 : layout.NS_MAX : dampers.N_DAMPER_STATES] = vcmd  # coils settled at the command
    P = np.tile(damper.pack() if damper is not None else np.zeros(dampers.N_PACKED), (n, 1))
    if initial_state is not None:
        x0 = np.asarray(initial_state, dtype=float)
        if x0.shape not in ((2 * N_DOF,), (n, 2 * N_DOF)) or not np.all(np.isfinite(x0)):
            raise InputError(
                f"initial_state must hold {2 * N_DOF} finite numbers (q then q') "
                f"or one such row per sample; got shape {x0.shape}"
            )
        x[:, : 2 * N_DOF] = x0
    out = {
        "q": np.empty((n, rows, N_DOF)),
        "v": np.empty((n, rows, N_DOF)),
        "a": np.empty((n, rows, N_DOF)),
        "f": np.empty((n, rows, 4)),
        "w": np.empty((n, rows, 8)),
        "wd": np.empty((n, rows, 8)),
        "d": np.empty((n, rows if has_damper_states(damper) else 1, layout.N_DS)),
        "fd": np.zeros((n, rows if closed is not None else 1, 4)),
        "vc": np.empty((n, rows if closed is not None else 1, 4)),
    }
    status = np.zeros(n, dtype=np.int64)
    fail_step = np.full(n, -1, dtype=np.int64)
    faults = fault_table([s.faults for s in suspensions], dt, duration)

    if closed is None:
        ctrl_stride, inner_gains, noise = 1, np.zeros((n, layout.N_INNER)), np.zeros((0, layout.NOISE_COLS))
    else:
        ctrl_stride, noise = closed["stride"], closed["noise"]
        inner = closed["inner"]  # none for the ideal devices: the stepper does not read it
        inner_gains = np.zeros((n, layout.N_INNER))  # the inner-loop row of each sample (layout.I_*)
        if inner is not None:
            inner_gains[:, layout.I_B], inner_gains[:, layout.I_G] = inner.B, inner.G
        inner_gains[:, layout.I_LAW] = modes
        inner_gains[:, layout.I_DELAY] = [s.delay for s in suspensions]
    chunk = n_steps if progress is None else max(stride, (_CHUNK_WORK // n) // stride * stride)
    done = 0
    if exact and closed is not None:
        from railride.engine.discrete import run_exact_closed

        closed_samples = [
            (
                _state_matrix(vehicles[id(p)], damper),  # the plant: C0, the force is the demand
                systems[id(p)]["Bw"],
                systems[id(p)]["Bwd"],
                vehicles[id(p)].T / np.diag(vehicles[id(p)].M)[:, None],
                gm[i],
                hm[i],
                suspensions[i].delay,
                utab[u_off[i] : u_off[i] + n_nodes[i]],
                interval[i],
            )
            for i, p in enumerate(param_sets)
        ]
        status, fail_step = run_exact_closed(out, closed_samples, x[:, : 2 * N_DOF], dt, stride, ctrl_stride, n_out)
        if progress is not None:
            progress(1.0)
    elif exact:
        from railride.engine.discrete import run_exact

        samples = [
            (
                vehicles[id(p)].state_matrix,
                systems[id(p)]["Bw"],
                systems[id(p)]["Bwd"],
                vehicles[id(p)].T,
                p.c_sz,
                utab[u_off[i] : u_off[i] + n_nodes[i]],
                interval[i],
            )
            for i, p in enumerate(param_sets)
        ]
        status, fail_step = run_exact(out, samples, x[:, : 2 * N_DOF], dt, stride, n_out)
        if progress is not None:
            progress(1.0)
    # a batch that fills groups of lanes.LANES samples runs them in vector form (run_lanes)
    if lanes.lanes_fit(n, P, sensing):
        step_batch = lanes.lanes_stepper(n, law, arrays["A"], arrays["TS"], P)
    else:
        step_batch = functools.partial(kernels.run_parallel, kernels.run_batch)
    stop = _StopRequest(progress is not None and not exact)
    # the stepper's argument groups (`kernels.run_batch`): vehicle, dampers, inputs, control, outputs
    kernel_groups = (
        (arrays["A"], arrays["TS"], arrays["c_sec"]),
        (P, vcmd),
        (utab, u_off, ftab, f_off, n_nodes, interval),
        (closed is not None, ctrl_stride, gm, hm, inner_gains, noise, faults, sensing, snoise),
        tuple(out[key] for key in ("q", "v", "a", "f", "w", "wd", "d", "fd", "vc")) + (status, fail_step),
    )
    step_batch = stop.around(step_batch)
    while not exact:
        todo = min(chunk, n_steps - done)
        final = done + todo == n_steps
        started = time.perf_counter()
        step_batch(n, law, x, done, todo, final, stride, dt, *kernel_groups)
        done += todo
        if progress is not None:
            took = max(time.perf_counter() - started, 1e-6)  # the first call may include compiling
            chunk = max(stride, min(4 * todo, int(todo * _CHUNK_SECONDS / took)) // stride * stride)
            progress(done / n_steps)
        if final or stop.requested:
            break
    if stop.requested:  # Ctrl-C: keep the output rows of the finished chunks
        rows = done // stride  # the row at `done` itself is written by the chunk after it
        if rows < 2:
            raise KeyboardInterrupt
        out = {key: v[:, :rows] if v.shape[1] > 1 else v for key, v in out.items()}
    diverged_at = np.full(n, np.nan)
    if np.any(status != layout.STATUS_OK):
        bad = np.flatnonzero(status != layout.STATUS_OK)
        which = ", ".join(f"sample {i} at t = {fail_step[i] * dt:.4g} s" for i in bad[:5])
        message = (
            f"the simulation diverged ({which}): a response left +-{layout.DIVERGED:g} "
            f"or stopped being finite; check the parameters or reduce dt"
        )
        if on_divergence != "mark":
            raise DivergenceError(message)
        for i in bad.tolist():  # the stepper stopped there: what follows is not a response
            diverged_at[i] = fail_step[i] * dt
            cut = fail_step[i] // stride
            for key in out:
                if out[key].shape[1] > 1:
                    out[key][i, cut:] = np.nan

    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    raw = {
        "time": np.arange(rows) / output_rate,
        "q": out["q"],
        "a": out["a"],
        "batch": batch,
        "diverged_at": diverged_at,
    }
    result = RideResult(
        raw=raw,
        build=functools.partial(
            build_dataset,
            out,
            vehicles,
            param_sets,
            scenarios,
            dt,
            output_rate,
            rows,
            batch,
            created,
            suspensions[0],
            vcmd,
            closed,
            [s.faults for s in suspensions],
            INTEGRATOR_EXACT if exact else INTEGRATOR_RK4,
        ),
        suspension=suspensions if batch else suspensions[0],
        solver=solver,
        scenario=scenarios if batch else scenarios[0],
        params=param_sets if batch else param_sets[0],
    )
    if stop.requested:
        until = (rows - 1) / output_rate
        marked = _marked_partial(result._build, f"interrupted: up to t = {until:.4g} s of {duration:.4g} s")
        object.__setattr__(result, "_build", marked)  # a RideResult is frozen; its Dataset is not built yet
        raise Interrupted(result, until)
    return result


class _StopRequest:
    """Ctrl-C while a chunk of the stepper runs, taken as a request to stop after it (the
    compiled chunk cannot be left half way) instead of a KeyboardInterrupt that would lose the
    chunks before it. Only in the main thread with Python's own handler in place, and from the
    second chunk on: the first is short and may compile the stepper, which Ctrl-C should stop
    at once. A second Ctrl-C raises at once; between chunks Ctrl-C is a KeyboardInterrupt."""

    def __init__(self, enabled: bool):
        import signal
        import threading

        self.requested = False
        self.enabled = (
            enabled
            and threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler
        )

    def _handler(self, signum, frame):
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    def around(self, step):
        if not self.enabled:
            return step
        import signal

        calls = []

        def guarded(*args):
            calls.append(None)
            if len(calls) == 1:
                return step(*args)
            signal.signal(signal.SIGINT, self._handler)
            try:
                return step(*args)
            finally:
                signal.signal(signal.SIGINT, signal.default_int_handler)

        return guarded


def _marked_partial(build, text: str):
    """``build`` of a result whose Dataset gets ``partial`` = ``text`` in its attrs."""

    def marked():
        dataset = build()
        dataset.attrs["partial"] = text
        return dataset

    return marked
