"""The one entry point: `simulate` runs one scenario or a batch and returns a `RideResult`,
through named stages: `check` (`railride.run.checks`), `inputs`, `pack`, `step`, `assemble`."""

from __future__ import annotations

import dataclasses
import functools
import time
from dataclasses import dataclass
from datetime import datetime, timezone

import numpy as np

from railride.engine import kernels, lanes, layout
from railride.errors import DivergenceError, InputError, Interrupted
from railride.model.track import table_key
from railride.engine.layout import N_DOF
from railride.run.checks import (  # noqa: F401  (max_stable_dt and the integrators' names: their home before)
    INTEGRATOR_EXACT,
    INTEGRATOR_RK4,
    RunPlan,
    _state_matrix,
    check,
    max_stable_dt,
)
from railride.run.inputs import (  # noqa: F401  (the stores, read here by tests and benchmarks)
    _FORCING_TABLES,
    _INPUT_TABLES,
    _forcing_table,
    _input_table,
    _system_arrays,
    _vehicle,
    engine_matrices,
    engine_state_matrix,
    forcing_identity,
    forcing_tables,
)
from railride.run.cores import CPU_THREADS
from railride.run.ride import RideResult, build_dataset, has_damper_states, ride_channels
from railride.secondary import dampers

#: sample-steps of the first kernel call when a progress callback is given; later calls are
#: sized to take about _CHUNK_SECONDS each, so that the callback, and Ctrl-C, which Python sees
#: only between calls, come a few times a second whatever the damper law costs per step
_CHUNK_WORK = 20_000
_CHUNK_SECONDS = 0.25


def simulate(
    scenario=None,
    params=None,
    suspension=None,
    *,
    vehicle=None,
    solver=None,
    initial_state=None,
    progress=None,
    on_divergence: str = "raise",
) -> "RideResult":
    """Simulate the vehicle on one or many scenarios.

    ``scenario`` is a `Scenario`, a scenario name (see `railride.model.track.scenario`) or a list of
    them; ``params`` (or ``vehicle=``, its other name) is a `VehicleParams`, a preset name, the
    path of a parameters file or a list; ``suspension`` a
    `railride.Suspension` (None: passive, the viscous dampers c_sz) or a list. Lists run as one
    batch along a ``sample`` dimension (a single item is broadcast against a list). Every
    sample of a batch must share the duration, and the suspensions of a batch one damper model,
    inner loop and sensor noise (`railride.secondary.suspension.batch_conflict`): a batch varies the
    constant voltages or the outer loops. MR dampers start with their coils at the command
    (v_min under a closed loop) and their hysteretic states at 0. A closed loop samples the
    carbody states at the solver's control rate.
    ``solver`` (`railride.SolverSettings`, default: its defaults) holds the fixed step dt
    [s] (RK4's, or the input grid's under the exact discretisation), the output rate [Hz] of
    the stored time histories and the controllers' rate [Hz].
    ``initial_state`` is (q, q') at t = 0 as 18 numbers in DOF order (m, rad, m/s, rad/s), or
    one row per sample; by default the vehicle starts at rest in equilibrium.
    ``progress(done_fraction)`` is called between chunks of a long run.
    A sample whose response leaves +-1000 (m or rad) or stops being finite has diverged: with
    ``on_divergence="raise"`` (the default) the run stops with a `railride.errors.DivergenceError`
    (a RuntimeError) giving the sample and the time; with ``"mark"`` (what studies use) the
    other samples stand, the diverged one's histories are NaN from that time on, and
    `RideResult.diverged_at` gives the time.

    A run goes through named stages, each a function of this module: `check` (every input,
    before any work: `railride.run.checks`), `inputs` (the stepper's matrices and the rail
    tables), `pack` (the stepper's arrays), `step` (the compiled engine, in chunks) and
    `assemble` (the `RideResult`).
    """
    from railride.model.params import vehicle_argument

    params = vehicle_argument(vehicle, params)
    return run(check(scenario, params, suspension, solver, on_divergence, initial_state), progress)


def run(plan: RunPlan, progress=None) -> RideResult:
    """The stages after `check`: a run of a checked `RunPlan` (what `compare` does with the
    plans it checked before its first run, so that nothing is checked twice)."""
    tables = inputs(plan)
    packed = pack(plan, tables)
    # the threads it steps on, held while it steps: a study's chunks in threads step one after
    # another where each fills the cores (`railride.run.cores`)
    with CPU_THREADS.taken(threads_used(plan, packed)):
        stepped = step(plan, tables, packed, progress)
    if plan.exact and reaches_stops(plan, stepped.out["q"], stepped.status):
        # the exact discretisation holds while the secondary stays off its bump stops: beyond
        # them the vehicle is not linear, and the run is stepped again by RK4
        from railride.run.checks import _check_dt

        if plan.solver.method == "exact":
            raise InputError(
                "method = 'exact': this run reaches the secondary bump stops (z_stop), where the "
                "vehicle is not linear; use method 'auto' (RK4 then) or 'rk4'"
            )
        for vehicle in plan.vehicles.values():
            _check_dt(vehicle, plan.solver.dt, plan.damper)
        return run(dataclasses.replace(plan, exact=False), progress)
    return assemble(plan, stepped)


def threads_used(plan: RunPlan, packed: Packed) -> int:
    """The CPU threads the step stage of this batch runs on: one per sample (per group of
    `lanes.LANES` samples on the lane stepper) up to numba's thread count; 0 on the GPU."""
    if stepped_on(plan) == "gpu":
        return 0
    units = plan.n
    if not plan.exact and lanes.lanes_fit(plan.n, packed.P, packed.control[7]):
        units = -(-plan.n // lanes.LANES)
    return kernels.threads_for(units)


def reaches_stops(plan: RunPlan, q: np.ndarray, status: np.ndarray) -> bool:
    """Whether any sample's secondary deflection (q, (n, rows, 9), through T) reaches its
    vehicle's bump-stop clearance (vehicles with stops only). A diverged sample does not count:
    it is reported as diverged, and its batch-mates keep the exact steps (one sample reaching
    the stops sends the whole batch to RK4, which agrees with them to its truncation error)."""
    for i, p in enumerate(plan.param_sets):
        if p.z_stop is not None and p.k_stop > 0.0 and status[i] == layout.STATUS_OK:
            travel = q[i] @ engine_matrices(plan.vehicles[id(p)])["T"]
            if np.nanmax(np.abs(travel), initial=0.0) >= p.z_stop:
                return True
    return False


# -- inputs ---------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Inputs:
    """The stepper's matrices per distinct vehicle (``systems``) and stacked per sample
    (``arrays``: A, TS, c_sec, stops), and the rail input and forcing tables of every sample, one
    table per scenario and vehicle that the samples share, concatenated, with each sample's
    offset, node count and node interval."""

    systems: dict
    arrays: dict
    utab: np.ndarray
    ftab: np.ndarray
    u_off: np.ndarray
    f_off: np.ndarray
    n_nodes: np.ndarray
    interval: np.ndarray


def inputs(plan: RunPlan) -> Inputs:
    """The inputs stage: the vehicles' matrices and the rail tables (kept for later batches
    within their byte budgets, `railride.run.inputs`)."""
    n, dt, duration, exact = plan.n, plan.solver.dt, plan.duration, plan.exact
    vehicles, param_sets = plan.vehicles, plan.param_sets
    systems = {key: _system_arrays(v, passive=plan.damper is None) for key, v in vehicles.items()}
    # each sample's copy taken from the distinct vehicles by index: one gather, not a stack of
    # a list as long as the batch
    order = {key: i for i, key in enumerate(systems)}
    which = np.array([order[id(p)] for p in param_sets], dtype=np.int64)
    arrays = {
        k: np.ascontiguousarray(np.stack([system[k] for system in systems.values()])[which])
        for k in ("A", "TS", "c_sec", "stops")
    }

    # rail inputs depend on the scenario and the wheelset spacing, the forcing also on the
    # vehicle: tables are shared between the samples that agree on those
    utabs: list[np.ndarray] = []
    forcing_jobs: list[tuple] = []
    u_index: dict[tuple, tuple] = {}
    f_index: dict[tuple, int] = {}
    u_off, f_job, n_nodes, interval = (
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n, dtype=np.int64),
        np.zeros(n),
    )
    keys: dict[int, object] = {}
    matrices = {key: forcing_identity(system) for key, system in systems.items()}  # once per vehicle
    for i, (sc, p) in enumerate(zip(plan.scenarios, param_sets)):
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
        if exact:  # the exact steps take the inputs themselves
            f_job[i] = -1
            continue
        # by the input matrices' values, not the vehicle (`forcing_identity`)
        system = systems[id(p)]
        fkey = (ukey, matrices[id(p)])
        if fkey not in f_index:
            f_index[fkey] = len(forcing_jobs)
            forcing_jobs.append((skey, lag, system["Bw"], system["Bwd"], matrices[id(p)], tab))
        f_job[i] = f_index[fkey]
    utab = np.ascontiguousarray(np.concatenate(utabs))
    ftab, starts = forcing_tables(forcing_jobs, dt, duration)
    f_off = np.array([starts[j] if j >= 0 else 0 for j in f_job], dtype=np.int64)
    return Inputs(systems, arrays, utab, ftab, u_off, f_off, n_nodes, interval)


# -- pack -----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Packed:
    """The stepper's arrays: the damper law, the state array ``x`` (q, q', damper, controller and
    sensor states per sample), the packed damper parameters ``P``, the outputs it writes
    (``out``, ``status``, ``fail_step``), and the control group (`kernels.run_batch`)."""

    law: int
    x: np.ndarray
    P: np.ndarray
    out: dict
    status: np.ndarray
    fail_step: np.ndarray
    control: tuple  # closed loop, control stride, G, H, inner loop rows, noise, faults, sensing, sensing noise


def pack(plan: RunPlan, tables: Inputs, rows: int | None = None) -> Packed:
    """The pack stage: the arrays the stepper reads and writes, allocated once. ``rows``: the
    rows of the histories it records (default the run's; the GPU's metrics-only runs take two,
    `railride.run.reduced`), one for those it does not."""
    n, damper, closed = plan.n, plan.damper, plan.closed
    rows = plan.n_out + 1 if rows is None else rows
    law = layout.LAW_VISCOUS_IN_C if damper is None else damper.law
    x = np.zeros((n, layout.NX))
    x[:, 2 * N_DOF + 2 : layout.NS_MAX : dampers.N_DAMPER_STATES] = plan.vcmd  # coils settled at the command
    P = np.tile(damper.pack() if damper is not None else np.zeros(dampers.N_PACKED), (n, 1))
    if plan.x0 is not None:
        x[:, : 2 * N_DOF] = plan.x0
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
    snoise = np.zeros((0, 4))
    if closed is None:
        ctrl_stride, inner_gains, noise = 1, np.zeros((n, layout.N_INNER)), np.zeros((0, layout.NOISE_COLS))
    else:
        ctrl_stride, noise, snoise = closed["stride"], closed["noise"], closed["snoise"]
        inner = closed["inner"]  # none for the ideal devices: the stepper does not read it
        inner_gains = np.zeros((n, layout.N_INNER))  # the inner-loop row of each sample (layout.I_*)
        if inner is not None:
            inner_gains[:, layout.I_B], inner_gains[:, layout.I_G] = inner.B, inner.G
        inner_gains[:, layout.I_LAW] = plan.modes
        inner_gains[:, layout.I_DELAY] = [s.delay for s in plan.suspensions]
    control = (closed is not None, ctrl_stride, plan.gm, plan.hm, inner_gains, noise, plan.faults, plan.sensing, snoise)
    return Packed(law, x, P, out, status, fail_step, control)


# -- step -----------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Stepped:
    """What the step stage leaves: the outputs (cut to the finished rows after Ctrl-C), each
    sample's status and failing step, the rows written, and whether Ctrl-C stopped the run."""

    out: dict
    status: np.ndarray
    fail_step: np.ndarray
    rows: int
    stopped: bool
    on: str = "CPU"  # what stepped it, for the record: the CPU, or the GPU by name


def step(plan: RunPlan, tables: Inputs, packed: Packed, progress=None) -> Stepped:
    """The step stage: the exact discretisation, or the compiled RK4 stepper (the lane stepper
    for batches that fill its groups) in chunks sized for ``progress`` and Ctrl-C."""
    n, dt, stride, n_steps = plan.n, plan.solver.dt, plan.stride, plan.n_steps
    out, status, fail_step = packed.out, packed.status, packed.fail_step
    x, vehicles, systems = packed.x, plan.vehicles, tables.systems
    utab, u_off, n_nodes, interval = tables.utab, tables.u_off, tables.n_nodes, tables.interval
    ctrl_stride = packed.control[1]
    rows = plan.n_out + 1
    if plan.exact and plan.closed is not None:
        from railride.engine.discrete import run_exact_closed

        closed_samples = [
            (
                _state_matrix(vehicles[id(p)], plan.damper),  # the plant: C0, the force is the demand
                systems[id(p)]["Bw"],
                systems[id(p)]["Bwd"],
                engine_matrices(vehicles[id(p)])["T"] / np.diag(engine_matrices(vehicles[id(p)])["M"])[:, None],
                plan.gm[i],
                plan.hm[i],
                plan.suspensions[i].delay,
                utab[u_off[i] : u_off[i] + n_nodes[i]],
                interval[i],
            )
            for i, p in enumerate(plan.param_sets)
        ]
        status, fail_step = run_exact_closed(
            out, closed_samples, x[:, : 2 * N_DOF], dt, stride, ctrl_stride, plan.n_out
        )
        if progress is not None:
            progress(1.0)
        return Stepped(out, status, fail_step, rows, False)
    if plan.exact:
        from railride.engine.discrete import run_exact

        samples = [
            (
                engine_state_matrix(vehicles[id(p)]),
                systems[id(p)]["Bw"],
                systems[id(p)]["Bwd"],
                engine_matrices(vehicles[id(p)])["T"],
                p.c_sz,
                utab[u_off[i] : u_off[i] + n_nodes[i]],
                interval[i],
            )
            for i, p in enumerate(plan.param_sets)
        ]
        status, fail_step = run_exact(out, samples, x[:, : 2 * N_DOF], dt, stride, plan.n_out)
        if progress is not None:
            progress(1.0)
        return Stepped(out, status, fail_step, rows, False)
    arrays, P = tables.arrays, packed.P
    # the GPU where the settings take it (`SolverSettings.backend_for`); on the CPU a batch that
    # fills groups of lanes.LANES samples runs them in vector form (run_lanes)
    on = "CPU"
    if stepped_on(plan) == "gpu":
        from railride.engine import gpu

        step_batch = gpu.stepper(_gpu_failed)
        on = f"GPU ({gpu.device_name()})"
    elif lanes.lanes_fit(n, P, packed.control[7]):
        step_batch = lanes.lanes_stepper(n, packed.law, arrays["A"], arrays["TS"], P, arrays["stops"])
    else:
        step_batch = functools.partial(kernels.run_parallel, kernels.run_batch)
    stop = _StopRequest(progress is not None)
    kernel_groups = stepper_arguments(plan, tables, packed)
    step_batch = stop.around(step_batch)
    chunk = n_steps if progress is None else max(stride, (_CHUNK_WORK // n) // stride * stride)
    done = 0
    try:
        while True:
            todo = min(chunk, n_steps - done)
            final = done + todo == n_steps
            started = time.perf_counter()
            step_batch(n, packed.law, x, done, todo, final, stride, dt, *kernel_groups)
            done += todo
            if progress is not None:
                took = max(time.perf_counter() - started, 1e-6)  # the first call may include compiling
                chunk = max(stride, min(4 * todo, int(todo * _CHUNK_SECONDS / took)) // stride * stride)
                progress(done / n_steps)
            if final or stop.requested:
                break
    finally:
        stop.restore()
    if stop.requested:  # Ctrl-C: keep the output rows of the finished chunks
        rows = done // stride  # the row at `done` itself is written by the chunk after it
        if rows < 2:
            raise KeyboardInterrupt
        out = {key: v[:, :rows] if v.shape[1] > 1 else v for key, v in out.items()}
    return Stepped(out, status, fail_step, rows, stop.requested, on)


def stepper_arguments(plan: RunPlan, tables: Inputs, packed: Packed) -> tuple:
    """The stepper's argument groups after its scalars (`kernels.run_batch`): vehicle, dampers,
    inputs, control, outputs."""
    arrays, out = tables.arrays, packed.out
    return (
        (arrays["A"], arrays["TS"], arrays["c_sec"], arrays["stops"]),
        (packed.P, plan.vcmd),
        (tables.utab, tables.u_off, tables.ftab, tables.f_off, tables.n_nodes, tables.interval),
        packed.control,
        tuple(out[key] for key in ("q", "v", "a", "f", "w", "wd", "d", "fd", "vc")) + (packed.status, packed.fail_step),
    )


def stepped_on(plan: RunPlan) -> str:
    """ "cpu" or "gpu": where the RK4 steps of this run go (the exact steps are always the CPU's)."""
    return "cpu" if plan.exact else plan.solver.backend_for(plan.n, plan.duration)


def _gpu_failed(exc: BaseException) -> None:
    """A GPU failure during a run: one warning line; the stepper finishes the chunk on the CPU."""
    import warnings

    from railride.errors import BackendWarning

    text = " ".join(str(exc).split())[:200] or type(exc).__name__
    warnings.warn(f"the GPU failed ({text}); the run goes on on the CPU", BackendWarning, 2)


# -- assemble -------------------------------------------------------------------------------------
def divergence_message(status: np.ndarray, fail_step: np.ndarray, dt: float) -> str:
    """What a `DivergenceError` says: the first samples that diverged, and when."""
    bad = np.flatnonzero(status != layout.STATUS_OK)
    which = ", ".join(f"sample {i} at t = {fail_step[i] * dt:.4g} s" for i in bad[:5])
    return (
        f"the simulation diverged ({which}): a response left +-{layout.DIVERGED:g} "
        f"or stopped being finite; check the parameters or reduce dt"
    )


def assemble(plan: RunPlan, stepped: Stepped) -> RideResult:
    """The assemble stage: divergence (raised, or marked with NaN from its time on), and the
    `RideResult`, whose Dataset is built when first asked for (`railride.run.ride.build_dataset`).
    A run stopped by Ctrl-C raises `railride.errors.Interrupted` holding the partial result."""
    n, dt, stride, output_rate = plan.n, plan.solver.dt, plan.stride, plan.solver.output_rate
    out, status, fail_step, rows = stepped.out, stepped.status, stepped.fail_step, stepped.rows
    diverged_at = np.full(n, np.nan)
    if np.any(status != layout.STATUS_OK):
        bad = np.flatnonzero(status != layout.STATUS_OK)
        if plan.on_divergence != "mark":
            raise DivergenceError(divergence_message(status, fail_step, dt))
        for i in bad.tolist():  # the stepper stopped there: what follows is not a response
            diverged_at[i] = fail_step[i] * dt
            cut = fail_step[i] // stride
            for key in out:
                if out[key].shape[1] > 1:
                    out[key][i, cut:] = np.nan

    created = datetime.now(timezone.utc).isoformat(timespec="seconds")
    batch, suspensions = plan.batch, plan.suspensions
    raw = {
        "time": np.arange(rows) / output_rate,
        "q": out["q"],
        "a": out["a"],
        "batch": batch,
        "diverged_at": diverged_at,
        # a few channels without the whole Dataset (`RideResult.channels`)
        "channels": functools.partial(
            ride_channels, out, plan.vehicles, plan.param_sets, suspensions[0].damper, plan.vcmd, plan.closed
        ),
    }
    result = RideResult(
        raw=raw,
        build=functools.partial(
            build_dataset,
            out,
            plan.vehicles,
            plan.param_sets,
            plan.scenarios,
            dt,
            output_rate,
            rows,
            batch,
            created,
            suspensions[0],
            plan.vcmd,
            plan.closed,
            [s.faults for s in suspensions],
            INTEGRATOR_EXACT
            if plan.exact
            else INTEGRATOR_RK4 + ("" if stepped.on == "CPU" else f", on the {stepped.on}"),
        ),
        suspension=suspensions if batch else suspensions[0],
        solver=plan.solver,
        scenario=plan.scenarios if batch else plan.scenarios[0],
        params=plan.param_sets if batch else plan.param_sets[0],
    )
    if stepped.stopped:
        until = (rows - 1) / output_rate
        marked = _marked_partial(result._build, f"interrupted: up to t = {until:.4g} s of {plan.duration:.4g} s")
        object.__setattr__(result, "_build", marked)  # a RideResult is frozen; its Dataset is not built yet
        raise Interrupted(result, until)
    return result


class _StopRequest:
    """Ctrl-C while the stepper runs its chunks, taken as a request to stop after the chunk it
    came in (the compiled chunk cannot be left half way) instead of a KeyboardInterrupt that
    would lose the chunks before it. Only in the main thread with Python's own handler in place,
    and once the first chunk has finished: the first is short and may compile the stepper,
    which Ctrl-C should stop at once. From then until `restore`, between chunks too (a Ctrl-C
    right after a progress report had raised, losing the run, where it came before the next
    chunk took the handler); a second Ctrl-C raises at once."""

    def __init__(self, enabled: bool):
        import signal
        import threading

        self.requested = False
        self.installed = False
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

        def guarded(*args):
            done = step(*args)
            if not self.installed:  # the first chunk has finished: Ctrl-C is a request from now on
                signal.signal(signal.SIGINT, self._handler)
                self.installed = True
            return done

        return guarded

    def restore(self) -> None:
        """Python's own Ctrl-C again, once the chunks are done (or one failed)."""
        if self.installed:
            import signal

            signal.signal(signal.SIGINT, signal.default_int_handler)
            self.installed = False


def _marked_partial(build, text: str):
    """``build`` of a result whose Dataset gets ``partial`` = ``text`` in its attrs."""

    def marked():
        dataset = build()
        dataset.attrs["partial"] = text
        return dataset

    return marked
