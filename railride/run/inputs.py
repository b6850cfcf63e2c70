"""The inputs of a run: the vehicle's stepper matrices, the wheelset input tables and the rail
forcing tables, each kept for the next batches within a byte budget (`railride._cache.BytesLRU`)."""

from __future__ import annotations

import functools
import weakref


import numpy as np

from railride._cache import MiB, BytesLRU
from railride.engine.layout import N_DOF
from railride.model.params import VehicleParams
from railride.model.track import Scenario, wheelset_input_table
from railride.model.vehicle import Vehicle


@functools.lru_cache(maxsize=256)
def _vehicle(params: VehicleParams) -> Vehicle:
    """Vehicles are derived from frozen parameters: build each one once."""
    return Vehicle(params)


#: the wheelset input tables kept for the next batches (`_input_table`): (nodes x 16) doubles,
#: 0.8 MB for 10 s at 30 m/s on a random track, 1.6 MB at 45 m/s, 3.2 MB at 65 m/s. A passive
#: chunk's 32 scenarios fit at the usual speeds, so the controllers' chunks on the same
#: scenarios, which run next to it (`railride.studies.sweep.run_cases`), find theirs. The
#: default design's 36 training conditions take 67.2 MB, read again every tuning round: a store
#: smaller than that kept none of them from one round to the next (the least recently used went
#: first, each just before it was wanted), so each round built its tables and tracks again
INPUT_CACHE_BYTES = 128 * MiB
#: the rail forcing tables kept (`_forcing`): (nodes x 36) doubles, 2.25 times the input table;
#: shared by the closed-loop runs of a scenario and vehicle, which a study puts in one batch,
#: and kept for the repeated rounds of tuning (a tuning set of about 16 scenarios and loads)
FORCING_CACHE_BYTES = 64 * MiB


_INPUT_TABLES: BytesLRU = BytesLRU("wheelset input tables", INPUT_CACHE_BYTES, lambda t: t[0].nbytes)
_FORCING_TABLES: BytesLRU = BytesLRU("rail forcing tables", FORCING_CACHE_BYTES, lambda t: t.nbytes)


def _input_table(scenario: Scenario, key, lag: tuple, dt: float, duration: float):
    """`wheelset_input_table` of ``scenario`` (its `table_key` ``key``), kept within
    `INPUT_CACHE_BYTES`: the batches of a study (passive beside each controller) meet the same
    scenario again. The tables are read, never written. A scenario without a key is not kept."""

    def build():
        table, interval = wheelset_input_table(scenario, np.asarray(lag), dt, duration)
        table.flags.writeable = False  # shared between runs
        return table, interval

    return _INPUT_TABLES.get(None if key is None else (key, lag, dt, duration), build)


#: each vehicle's matrices at the engine's size, made once: a batch's samples share the vehicle
_ENGINE_MATRICES: "weakref.WeakKeyDictionary[Vehicle, dict[str, np.ndarray]]" = weakref.WeakKeyDictionary()


def engine_matrices(vehicle: Vehicle) -> dict[str, np.ndarray]:
    """The vehicle's M, K, C, C0, T, K_w, C_w at the engine's size (`layout.N_DOF`), and its
    passive state matrix ``A`` (q, q'), made once per vehicle (read them, do not write): a rigid
    carbody's vehicle (`Vehicle.n_dof` 9) gets a bending row and column of zeros with a unit
    mass, so that its bending coordinate stays exactly 0; a flexible one is the engine's size."""
    cached = _ENGINE_MATRICES.get(vehicle)
    if cached is not None:
        return cached
    n = vehicle.M.shape[0]
    out = {}
    for k in ("M", "K", "C", "C0", "T", "K_w", "C_w"):
        v = getattr(vehicle, k)
        square = v.shape[1:] == (n,)  # pad the columns too
        out[k] = np.zeros((N_DOF, N_DOF) if square else (N_DOF,) + v.shape[1:])
        if square:
            out[k][:n, :n] = v
        else:
            out[k][:n] = v
    out["M"][n:, n:] = np.eye(N_DOF - n)
    minv = 1.0 / np.diag(out["M"])[:, None]
    A = np.zeros((2 * N_DOF, 2 * N_DOF))
    A[:N_DOF, N_DOF:] = np.eye(N_DOF)
    A[N_DOF:, :N_DOF] = -minv * out["K"]
    A[N_DOF:, N_DOF:] = -minv * out["C"]
    out["A"] = A
    _ENGINE_MATRICES[vehicle] = out
    return out


def engine_state_matrix(vehicle: Vehicle) -> np.ndarray:
    """The passive state matrix (q, q') at the engine's size (`engine_matrices`), with the
    secondary dashpots."""
    return engine_matrices(vehicle)["A"]


def _system_arrays(vehicle: Vehicle, passive: bool = True) -> dict[str, np.ndarray]:
    """The stepper's matrices: the equations of motion with M^-1 folded in, transposed
    (see `railride.engine.kernels.run_batch`).

    ``A`` = [Aq Av Bf]^T acts on (q, q', f), ``TS`` = T maps q' to the secondary deflection
    rates. The passive viscous dampers are linear, so they stay in Av (law LAW_VISCOUS_IN_C):
    the stepper then skips the force computation per stage; with damper models (``passive``
    false) Av leaves them out and their forces enter through Bf. ``Bw``, ``Bwd`` map the rail
    inputs to q'' and are applied to the input table once, before the run.
    """
    m = engine_matrices(vehicle)
    minv = 1.0 / np.diag(m["M"])[:, None]
    return {
        "A": np.hstack([-minv * m["K"], -minv * (m["C"] if passive else m["C0"]), minv * m["T"]]).T,
        "TS": m["T"].copy(),
        "c_sec": np.full(4, vehicle.params.c_sz),
        # the bump stops (clearance, stiffness; stiffness 0: none), `railride.engine.laws.stop_force`
        "stops": _stops(vehicle.params),
        "Bw": -minv * m["K_w"],
        "Bwd": -minv * m["C_w"],
    }


def _stops(params: VehicleParams) -> np.ndarray:
    """The engine's (clearance, stiffness) of the bump stops: an infinite clearance and no
    stiffness where there are none (a stiffness of 0, or no clearance)."""
    if params.z_stop is None or params.k_stop == 0.0:
        return np.array([np.inf, 0.0])
    return np.array([params.z_stop, params.k_stop])


def _forcing_table(utab: np.ndarray, Bw: np.ndarray, Bwd: np.ndarray) -> np.ndarray:
    """Node values (Bw w, Bw w', Bwd w, Bwd w') of the rail forcing, see kernels._forcing:
    compiled (`railride.engine.tables.forcing_nodes`), without the GIL and skipping the input
    matrices' zeros (two thirds of them). Not a threaded BLAS ``@``: on these thin products it
    took 90-130 ms instead of 6-10 ms while other work kept the cores busy."""
    out = np.empty((utab.shape[0], 4 * Bw.shape[0]))
    _fill_forcing([(utab, Bw, Bwd, out)])
    return out


#: the rows of one piece of a forcing table that a thread builds (`_fill_forcing`): a table of a
#: 20 s run at 70 m/s has 50,000 nodes
_FORCING_PIECE_ROWS = 16_384


def _fill_forcing(work) -> None:
    """`forcing_nodes` for each (utab, Bw, Bwd, out) of ``work``, in pieces of rows over numba's
    threads (`run_each`): the tables of a tuning round (18 for the default design, 168 MB)
    are the host's largest work beside a GPU. Each node is its own sum, so a piece gives the
    rows the whole table would."""
    from railride.engine.kernels import run_each
    from railride.engine.tables import forcing_nodes

    pieces = []
    for utab, Bw, Bwd, out in work:
        table = np.ascontiguousarray(utab).view()
        table.flags.writeable = False  # one compiled signature: the kept tables are read-only
        Bw, Bwd = np.ascontiguousarray(Bw), np.ascontiguousarray(Bwd)
        for lo in range(0, table.shape[0], _FORCING_PIECE_ROWS):
            hi = min(lo + _FORCING_PIECE_ROWS, table.shape[0])
            pieces.append((table[lo:hi], Bw, Bwd, out[lo:hi]))
    run_each(lambda i: forcing_nodes(*pieces[i]), len(pieces))


def forcing_identity(system: dict) -> bytes:
    """The values of a vehicle's input matrices (`_system_arrays`' ``Bw``, ``Bwd``), by which its
    forcing tables are shared and kept: a payload changes the carbody, which no wheelset
    reaches, so a design's loads share their tables."""
    return system["Bw"].tobytes() + system["Bwd"].tobytes()


def forcing_tables(jobs, dt: float, duration: float) -> tuple[np.ndarray, list[int]]:
    """The rail forcing tables of a batch in one array, and the row where each begins: one table
    (`_forcing_table`) for each (key, lag, Bw, Bwd, matrices, table) of ``jobs``, the input
    ``table`` of the scenario with `table_key` ``key`` and wheelset lags ``lag``, and a vehicle's
    input matrices ``Bw``, ``Bwd`` (`_system_arrays`), whose values ``matrices`` identify
    (`forcing_identity`). Tables kept from earlier batches (within
    `FORCING_CACHE_BYTES`, by the matrices' values: vehicles that differ only where no wheelset
    reaches share them) are copied in; the others are built in place, over every core, and kept
    only where the batch's tables fit the store: a larger set (a tuning round's) would push each
    other out, and each would be a copy more."""
    if not jobs:
        return np.zeros((1, 4 * N_DOF)), []
    offsets, total = [], 0
    for *_, table in jobs:
        offsets.append(total)
        total += len(table)
    ftab = np.empty((total, 4 * N_DOF))
    keep = ftab.nbytes <= _FORCING_TABLES.budget
    work, built = [], []
    for (key, lag, Bw, Bwd, matrices, table), off in zip(jobs, offsets):
        out = ftab[off : off + len(table)]
        store_key = None if key is None else (key, lag, dt, duration, matrices)
        kept = _FORCING_TABLES.lookup(store_key)
        if kept is not None:
            out[...] = kept
            continue
        work.append((table, Bw, Bwd, out))
        built.append((store_key, out))
    _fill_forcing(work)
    if keep:
        for store_key, out in built:
            if store_key is not None:
                table = out.copy()
                table.flags.writeable = False
                _FORCING_TABLES.put(store_key, table)
    return ftab, offsets
