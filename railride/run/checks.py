"""The check stage of a run: `check` takes what `simulate` was given, checks every input before
anything is allocated or stepped, and resolves names and defaults into a `RunPlan`, which the
later stages (`railride.run.simulation`: inputs, pack, step, assemble) read. `compare` checks
its runs with it too, so that each setting is checked in one place."""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from railride import limits
from railride.defaults import DEFAULT_DT
from railride.engine import lanes, layout
from railride.errors import InputError
from railride.model.params import VehicleParams
from railride.model.track import Scenario, as_scenario, input_table_nodes, table_key
from railride.engine.layout import N_DOF, N_RIGID
from railride.model.vehicle import Vehicle
from railride.run.inputs import _vehicle, engine_matrices, engine_state_matrix
from railride.run.ride import has_damper_states
from railride.run.solver import SolverSettings, check_resolution
from railride.secondary import dampers
from railride.secondary.faults import fault_table
from railride.secondary.control import outer_gains
from railride.secondary.sensing import reads_bogies
from railride.secondary.suspension import Suspension, batch_conflict
from railride.validation import shown


def _rk4_gain(z: np.ndarray) -> np.ndarray:
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


@functools.lru_cache(maxsize=256)
def _max_stable_dt(params: VehicleParams, damper=None) -> float:
    return max_stable_dt(_vehicle(params), damper)


def _state_matrix(vehicle: Vehicle, damper=None) -> np.ndarray:
    """The passive state matrix (at the engine's size, `railride.run.inputs.engine_matrices`),
    or with MR dampers the vehicle linearised about their stiffest
    state: pre-yield stiffness k0 + k1 + alpha(v_max) A and damping c0(v_max) + c1(v_max). Their
    internal states are sub-stepped by the stepper and do not enter here."""
    if damper is None:
        return engine_state_matrix(vehicle)
    if damper.law == dampers.LAW_IDEAL:
        # its force is the held demand, a forcing term to the integrator: C0 without a damper
        k_eff, c_eff = 0.0, 0.0
    elif damper.law == dampers.LAW_VISCOUS:
        k_eff, c_eff = 0.0, damper.c
    else:
        v = damper.v_max
        k_eff = damper.k0 + getattr(damper, "k1", 0.0) + (damper.alpha_a + damper.alpha_b * v) * damper.A
        c_eff = damper.c0a + damper.c0b * v + getattr(damper, "c1a", 0.0) + getattr(damper, "c1b", 0.0) * v
    m = engine_matrices(vehicle)  # at the engine's size: the exact steps of the closed loop take it
    TT = m["T"] @ m["T"].T
    K = m["K"] + k_eff * TT
    C = m["C0"] + c_eff * TT
    minv = 1.0 / np.diag(m["M"])[:, None]
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


#: steps of dt per period of the carbody's bending, and output samples per period, at the least
BENDING_STEPS = 20
BENDING_SAMPLES = 4


def _check_bending(params: VehicleParams, solver: SolverSettings) -> None:
    """The step and the output rate must resolve a flexible carbody's bending mode: at least
    `BENDING_STEPS` steps and `BENDING_SAMPLES` output samples per period (RK4's phase error
    at 20 steps per period is below 1e-4 of a cycle; fewer samples alias the mode)."""
    f = params.bending_hz
    if f is None:
        return
    field = "f_bend" if params.f_bend is not None else "EI_c"
    if solver.dt * f * BENDING_STEPS > 1.0 + 1e-9:
        raise InputError(
            f"vehicle parameter {field!r}: the carbody bends at {shown(f)} Hz, which dt = {shown(solver.dt)} s "
            f"does not resolve; use dt <= {shown(1.0 / (BENDING_STEPS * f))} s ({BENDING_STEPS} steps per period)"
        )
    if solver.output_rate < BENDING_SAMPLES * f - 1e-9:
        raise InputError(
            f"vehicle parameter {field!r}: the carbody bends at {shown(f)} Hz, which output_rate = "
            f"{shown(solver.output_rate)} Hz does not resolve; use output_rate >= {shown(BENDING_SAMPLES * f)} Hz"
        )


def _exact_phases(scenarios, solver: SolverSettings, duration: float) -> tuple[int, int]:
    """(maps, m): the step maps the exact discretisation would build for these scenarios, the
    phases of the output steps against the input table's node spacing of m steps (that of the
    scenario with the most nodes)."""
    stride = solver.output_steps
    _, interval = max(input_table_nodes(sc, solver.dt, duration) for sc in scenarios)
    m = int(round(interval / solver.dt))
    return math.lcm(stride, m) // stride, m


def history_bytes(samples: int, rows: int, damper_states: bool = True, closed: bool = True) -> float:
    """Bytes of the time histories of ``samples`` runs of ``rows`` output rows each: the stepper's
    output channels (q, q', q'', the rail inputs, the damper forces; the damper states with
    ``damper_states``, the demands and commands of a closed loop with ``closed``)."""
    channels = 3 * N_DOF + 4 + 16 + (layout.N_DS if damper_states else 0) + (8 if closed else 0)
    return 8.0 * samples * rows * channels


def _check_size(
    scenarios, solver: SolverSettings, damper, closed, exact: bool, n_out: int, duration: float, tables=None
):
    """`railride.limits.check` on what a run allocates before it allocates it: the stored
    histories (samples x output rows x channels), the rail input and forcing tables, and the
    exact stepper's maps (one per phase of the output steps against the table's nodes). Given
    ``tables``, the number of distinct tracks and vehicles of a metrics-only run on the GPU
    (`railride.run.reduced`): two rows a sample, and that many tables."""
    n, dt, stride = len(scenarios), solver.dt, solver.output_steps
    limits.check_steps("dt", n_out * stride, "raise dt or shorten the run")
    need = history_bytes(n, (n_out + 1) if tables is None else 2, has_damper_states(damper), closed is not None)
    nodes, interval = max(input_table_nodes(sc, dt, duration) for sc in scenarios)
    need += 8.0 * (n if tables is None else tables) * nodes * (16 + 36)  # input, forcing tables: one a sample at most
    if exact:  # discrete.ExactStepper: period x 18 x (span x 8)
        period, m = _exact_phases(scenarios, solver, duration)
        span = (stride + m - 1) // m + 2
        need += 8.0 * period * 2 * N_DOF * span * 8
    limits.check(
        need,
        f"{n} run(s) of {duration:.4g} s at dt {dt:.4g} s ({n_out + 1} output samples, {nodes} input nodes)",
        # what a single run can change: no batch to split, and a dt at the default is no lever
        "shorten the duration or lower output_rate"
        + (", or run fewer samples at once" if n > 1 else "")
        + (" or use a dt nearer the default" if dt < DEFAULT_DT else ""),
    )
    if exact and period > _MAX_EXACT_PHASES:  # each phase costs matrix exponentials, 1-2 ms each
        raise InputError(
            f"dt = {shown(dt)} s: the exact discretisation would build {period} step maps (the output "
            f"interval, {stride} steps, and the input table's node spacing, {m} steps, line up again "
            f"only every {period} output samples); use method 'rk4', or 'auto', which takes RK4 there"
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
    if x is None or isinstance(x, (Scenario, VehicleParams, str, os.PathLike)) or not hasattr(x, "__iter__"):
        return [x]
    return list(x)


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


def _full_state_gains(G, controller) -> np.ndarray:
    """The outer loop's G as a map from the engine's whole state (q, q') (4 x 2 N_DOF): a law on
    the carbody states alone gives G over (z_c, phi_c, theta_c, z_c', phi_c', theta_c') (4 x 6),
    one on the whole state over the vehicle's (q, q') (4 x 2 n, `Vehicle.n_dof`)."""
    G = np.asarray(G, dtype=float)
    full = np.zeros((4, 2 * N_DOF))
    if G.shape in ((4, 2 * N_RIGID), (4, 2 * N_DOF)):  # on the vehicle's (q, q'): to the engine's
        n = G.shape[1] // 2
        full[:, :n], full[:, N_DOF : N_DOF + n] = G[:, :n], G[:, n:]
        return full
    if G.shape != (4, 6):
        raise InputError(
            f"controller {getattr(controller, 'name', controller)!r}: gains(vehicle) gave G of shape {G.shape}; "
            f"allowed (4, 6) on the carbody states or (4, 2 n) on the vehicle's (q, q'), n = {N_RIGID} "
            f"(a rigid carbody) or {N_DOF} (a flexible one)"
        )
    full[:, :3], full[:, N_DOF : N_DOF + 3] = G[:, :3], G[:, 3:]
    return full


@dataclass(frozen=True, eq=False)
class RunPlan:
    """A run as `check` found it: every sample's scenario, vehicle parameters and suspension (a
    single item broadcast against the batch), the solver, and what follows from them: the
    vehicles, the shared damper model, the closed loop's settings and each sample's outer-loop
    gains, whether the exact discretisation runs, the number of output rows and the initial
    state. Read by the later stages; nothing in it is allocated for the run yet."""

    batch: bool
    scenarios: list
    param_sets: list
    suspensions: list
    solver: SolverSettings
    duration: float
    damper: Any  # the batch's damper model (None: the viscous c_sz)
    closed: dict | None  # `_closed_loop`: None for an open loop
    exact: bool
    vehicles: dict  # id(parameters) -> Vehicle, one per distinct parameter set
    n_out: int  # output intervals (the histories hold n_out + 1 rows)
    vcmd: np.ndarray  # (n, 4) the command each sample's coils start at
    gm: np.ndarray  # (n, 4, 18) each sample's outer loop on (q, q')
    hm: np.ndarray  # (n, 4, 3) and on the integral of (z, phi, theta)
    modes: np.ndarray  # (n,) each sample's voltage law (layout.VOLTAGE_LAWS)
    sensing: np.ndarray  # (n, layout.SENSING_COLS) each sample's sensing row
    x0: np.ndarray | None  # the initial (q, q'), one row or one per sample; None: at rest
    faults: np.ndarray  # the engine's fault table (`railride.secondary.faults.fault_table`)
    on_divergence: str  # "raise" or "mark" (`railride.simulate`)

    @property
    def n(self) -> int:
        return len(self.scenarios)

    @property
    def stride(self) -> int:
        return self.solver.output_steps

    @property
    def n_steps(self) -> int:
        return self.n_out * self.stride


def check(
    scenario=None, params=None, suspension=None, solver=None, on_divergence="raise", initial_state=None, histories=True
):
    """Every input of `railride.simulate` checked, before any work: an InputError names the
    first that is wrong. Returns the `RunPlan` of the run. ``histories=False``: the run keeps
    only its metrics where it steps on the GPU (`railride.run.reduced.batch_metrics`), and its
    memory is checked for that."""
    solver = SolverSettings.of(solver)
    dt, output_rate = solver.dt, solver.output_rate
    if on_divergence not in ("raise", "mark"):
        raise InputError(
            f"on_divergence = {on_divergence!r}: allowed 'raise' (stop with an error) "
            "or 'mark' (keep the other samples; see RideResult.diverged_at)"
        )
    if isinstance(params, Vehicle):  # a vehicle stands for its parameters: one, not a batch
        params = params.params
    batch = (
        not (isinstance(scenario, (Scenario, str)) or scenario is None)
        or not (isinstance(params, (VehicleParams, str, os.PathLike)) or params is None)
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
    # the count of output samples first: the checks below make ints of the run's length
    # (1e308 s is no int)
    n_out = output_samples(duration, output_rate)
    conflict = batch_conflict(suspensions)
    if conflict is not None:
        raise InputError(conflict)
    damper = suspensions[0].damper
    voltages = {id(s): _command_voltage(s) for s in suspensions}  # a batch repeats its suspensions
    vcmd = np.array([[voltages[id(s)]] * 4 for s in suspensions], dtype=float)
    closed = _closed_loop(suspensions, solver, duration)
    exact = _exact(solver, damper, closed, suspensions, len(set(param_sets)))
    if exact and solver.method == "auto" and _exact_phases(scenarios, solver, duration)[0] > _MAX_EXACT_PHASES:
        exact = False  # "auto" takes RK4 where the exact steps would need too many maps (a slow speed)
    vehicles = {}
    for p in param_sets:
        if id(p) not in vehicles:
            vehicles[id(p)] = _vehicle(p)
            _check_bending(p, solver)
            if not exact:  # the exact steps are stable at any dt
                _check_dt(vehicles[id(p)], dt, damper)
    for sc in scenarios:  # the track's shortest wavelength must show in the output
        check_resolution(sc, output_rate)
    tables = None
    if not histories and not exact and solver.backend_for(n, duration) == "gpu":  # metrics summed on the device
        pairs = {(id(sc), id(p)): (sc, p) for sc, p in zip(scenarios, param_sets)}  # a batch repeats them
        tables = len({(table_key(sc) or id(sc), id(p)) for sc, p in pairs.values()})
    _check_size(scenarios, solver, damper, closed, exact, n_out, duration, tables)
    gm, hm, modes, sensing = _outer_loops(closed, param_sets, vehicles, n)
    faults = fault_table([s.faults for s in suspensions], dt, duration)  # their times within the run
    x0 = None
    if initial_state is not None:
        rule = f"{2 * N_RIGID} finite numbers (q then q'; {2 * N_DOF} with the carbody's bending)"
        try:
            x0 = np.asarray(initial_state, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise InputError(f"initial_state = {shown(initial_state)[:80]}: must hold {rule}") from None
        sizes = ((2 * N_RIGID,), (n, 2 * N_RIGID), (2 * N_DOF,), (n, 2 * N_DOF))
        if x0.shape not in sizes or not np.all(np.isfinite(x0)):
            raise InputError(
                f"initial_state must hold {2 * N_RIGID} finite numbers (q then q'; {2 * N_DOF} with the "
                f"carbody's bending after the nine rigid DOFs) or one such row per sample; got shape {x0.shape}"
            )
        if x0.shape[-1] == 2 * N_RIGID:  # the bending at rest
            padded = np.zeros(x0.shape[:-1] + (2 * N_DOF,))
            padded[..., :N_RIGID], padded[..., N_DOF : N_DOF + N_RIGID] = x0[..., :N_RIGID], x0[..., N_RIGID:]
            x0 = padded
    return RunPlan(
        batch, scenarios, param_sets, suspensions, solver, duration, damper, closed, exact, vehicles, n_out, vcmd,
        gm, hm, modes, sensing, x0, faults, on_divergence,
    )  # fmt: skip


def output_samples(duration: float, output_rate: float) -> int:
    """The output samples of a run of ``duration`` [s] stored at ``output_rate`` [Hz]: a whole
    number from 1 to `railride.limits.MAX_STEPS`, else InputError naming ``duration``."""
    n_out_f = duration * output_rate
    if not n_out_f <= limits.MAX_STEPS:  # inf or beyond any run: no int of it
        raise InputError(
            f"duration = {duration:g} s at output rate {output_rate:g} Hz is {n_out_f:.3g} output samples, more "
            f"than a run can count (at most {limits.MAX_STEPS:.4g}); shorten the run"
        )
    n_out = int(round(n_out_f))
    if abs(n_out - n_out_f) > 1e-6 * max(1.0, n_out_f) or n_out < 1:
        raise InputError(f"duration = {duration:g} s must be a whole number of output intervals (1/{output_rate:g} Hz)")
    return n_out


def _outer_loops(closed, param_sets, vehicles, n: int):
    """Each sample's outer loop on (q, q') and on the integral, its voltage law and its sensing
    row (zeros in open loop); a law that reads the bogies with accelerometers is refused."""
    gm = np.zeros((n, 4, 2 * N_DOF))
    hm = np.zeros((n, 4, 3))
    modes = np.zeros(n)  # the voltage law of each sample (dampers.VOLTAGE_LAWS)
    sensing = np.zeros((n, layout.SENSING_COLS))
    if closed is not None:
        made: dict[tuple, tuple] = {}  # a controller and vehicle that samples share: their gains once
        for i, (c, p) in enumerate(zip(closed["controllers"], param_sets)):
            key = (id(c), id(p))  # both held by the lists for the whole loop
            if key not in made:
                G, H = outer_gains(c, vehicles[id(p)])
                made[key] = (_full_state_gains(G, c), H)
            gm[i], hm[i] = made[key]
            modes[i] = dampers.VOLTAGE_LAWS.index(getattr(c, "voltage_law", "tracking"))
            if closed["sensing"] is not None:
                if reads_bogies(gm[i]):
                    raise InputError(
                        f"sensing with controller {c.name!r}: it reads the bogies' states, and the "
                        "accelerometers are on the carbody only (railride.secondary.sensing)"
                    )
                sensing[i] = closed["sensing"].pack(vehicles[id(p)].T[:3])  # the rigid carbody's map
    return gm, hm, modes, sensing
