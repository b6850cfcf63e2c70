"""Whether the compiled engine still has to be compiled, and a watch on its compiles.

numba compiles a kernel on its first call and caches the machine code (``cache=True``; next to
the engine in ``railride/engine/__pycache__``, or in ``NUMBA_CACHE_DIR``). A fresh install has no
cache, so its first closed-loop run would compile the stepper (`railride.engine.kernels.run_batch`),
some ten seconds; later processes load it at once. The package's build therefore compiles the
kernels `railride compare` needs (`build_cache`, run by setup.py), and the wheel carries their
machine code: after ``pip install .`` on this machine nothing is compiled. This module
answers, without compiling anything, whether a kernel is ready (`needs_compiling`), and lets a
front end hear when a compile starts (`watch_compiles`): the command line uses it to say so on
stderr; the library itself prints nothing.
"""

from __future__ import annotations

import contextlib
from typing import Callable, Iterator


#: seconds each kernel takes to compile (docs/performance.md, "Cold start", re-measured
#: 2026-11-28 on a 2-core VM: run_batch 34.6-44.4 s, run_lanes 26.6 s); the kernels not named
#: compile in about a second and go unannounced (run_lanes: batches of lanes.LANES samples or
#: more, e.g. `compare --controllers all`)
COMPILE_SECONDS = {"run_batch": 40.0, "run_lanes": 27.0}

#: the closed-loop RK4 stepper: MR dampers, ideal devices, controllers
STEPPER = "run_batch"

#: the modules that hold the compiled kernels
_MODULES = ("railride.engine.kernels", "railride.engine.lanes", "railride.engine.exact_kernels")


def _signatures() -> dict[str, tuple]:
    """The argument types with which the library calls each kernel that `railride compare` and
    the studies need (checked by a test against the calls themselves): what `build_cache`
    compiles. The lane stepper runs every batch of eight samples or more (sweeps, tuning)."""
    from numba import types

    i, f, b = types.int64, types.float64, types.boolean

    def a(ndim, dtype=f, layout="C"):
        return types.Array(dtype, ndim, layout)

    # run_batch's argument groups (tuples), shared by run_lanes but for the vehicle and the damper
    inputs = types.Tuple((a(2), a(1, i), a(2), a(1, i), a(1, i), a(1)))  # utab, u_off, ftab, f_off, n_nodes, interval
    # closed_loop, ctrl_stride, Gm, Hm, inner, noise, faults, sensing, snoise
    control = types.Tuple((b, i, a(3), a(3), a(2), a(2), a(2, i), a(2), a(2)))
    outputs = types.Tuple((a(3),) * 9 + (a(1, i), a(1, i)))  # nine outputs, status, fail_step
    run = (i, i, i, a(2), i, i, b, i, f)  # lo, hi, law, x, step0, n_steps, final, stride, dt
    return {
        # the run, vehicle = (A, TS, c_sec, stops), dampers = (P, vcmd), inputs, control, outputs
        "run_batch": run + (types.Tuple((a(3), a(3), a(2), a(2))), types.Tuple((a(2), a(2))), inputs, control, outputs),
        # lo, hi, lane_smp, lane_own, then run_batch's arguments after hi, with vehicle = the q'' product's
        # structure and values (a_ptr, a_col, a_val, a_uni), the corner product's (t_*), c_sec, stops;
        # dampers = (P, vcmd); last, the metric sums (reduce, win, acc)
        "run_lanes": (i, i, a(2, i), a(2, b))
        + run[2:]
        + (
            types.Tuple((a(1, i), a(1, i), a(3), a(1, b), a(1, i), a(1, i), a(3), a(1, b), a(2), a(2))),
            types.Tuple((a(1), a(2))),
            inputs,
            control,
            outputs,
            types.Tuple((b, a(1, i), a(2))),
        ),
        # Phi (a slice), maps, used, stride, m, utab, interval, x0, A, Bw, Bwd, TS, c_sec, six outputs
        "exact_run": (a(2, layout="A"), a(3), a(1, i), i, i, a(2), f, a(1), a(2), a(2), a(2), a(2), a(1)) + (a(2),) * 6,
        # phi, rail, force, start, period, m, stride, ctrl, tc, utab, interval, x0, A, Bw, Bwd, Bf, G,
        # H, delay, n_out, eight outputs
        "exact_closed_run": (a(3), a(3), a(3), a(1, i), i, i, i, i, f, a(2), f, a(1))
        + (a(2),) * 6
        + (i, i)
        + (a(2),) * 8,
        # a random track's rails at the wheelsets: breakpoints, two coefficient arrays, s, out
        "cubic_on_grid": (a(1), a(2), a(2), a(1), a(2)),
        # the rail forcing at the input table's nodes: utab, Bw, Bwd, out
        "forcing_nodes": (types.Array(f, 2, "C", readonly=True), a(2), a(2), a(2)),
    }


def build_cache(kernels: tuple[str, ...] | None = None) -> list[str]:
    """Compile the kernels `railride compare` and the studies need into numba's cache, unless it already holds
    them; return the names compiled or loaded. The package's build runs this (setup.py), so
    that the machine code ships inside the installed package and the first run after
    ``pip install .`` starts at once. Compiling takes about as long as the first run would."""
    sigs = _signatures()
    names = list(sigs) if kernels is None else list(kernels)
    for name in names:
        _dispatcher(name).compile(sigs[name])
    return names


def _dispatcher(kernel: str):
    from railride.engine import exact_kernels, kernels, lanes, tables

    found = {
        n: v
        for m in (kernels, lanes, exact_kernels, tables)
        for n, v in vars(m).items()
        if hasattr(v, "py_func") and not n.startswith("_")
    }
    if kernel not in found:
        raise ValueError(f"kernel = {kernel!r}: not a compiled kernel; one of {', '.join(sorted(found))}")
    return found[kernel]


def needs_compiling(kernel: str = STEPPER) -> bool:
    """Whether the next call of ``kernel`` (a name in `railride.engine.kernels` or
    `railride.engine.lanes`) compiles it: False when this process has compiled or loaded it, or
    when numba's cache holds machine code for this source, this numba and this processor; True
    otherwise. Compiles nothing."""
    dispatcher = _dispatcher(kernel)
    if dispatcher.signatures:
        return False
    cache = getattr(dispatcher, "_cache", None)
    cache_file = getattr(cache, "_cache_file", None)
    if cache is None or cache_file is None:  # caching off: every process compiles
        return True
    try:
        index = cache_file._load_index()  # {} when absent, stale (source changed) or another numba
        magic = dispatcher.targetctx.codegen().magic_tuple()  # the processor and its features
        code = cache._index_key((), dispatcher.targetctx.codegen())[2]  # the bytecode's hash
    except Exception:  # noqa: BLE001  numba's cache internals moved: assume the worst
        return True
    return not any(key[1] == magic and key[2] == code for key in index)


def compile_seconds(kernel: str = STEPPER) -> float:
    """About how long ``kernel`` takes to compile (0 for the kernels that compile in about a
    second)."""
    _dispatcher(kernel)
    return COMPILE_SECONDS.get(kernel, 0.0)


@contextlib.contextmanager
def watch_compiles(on_start: Callable[[str], None]) -> Iterator[None]:
    """Within the block, call ``on_start(kernel)`` when numba starts compiling one of the
    kernels named in `COMPILE_SECONDS` (not when it loads one from its cache). The call may come
    from a worker thread (batches run on threads)."""
    from numba.core import event

    class _Listener(event.Listener):
        def on_start(self, ev):
            func = getattr(ev.data.get("dispatcher"), "py_func", None)
            if getattr(func, "__module__", "") in _MODULES and func.__name__ in COMPILE_SECONDS:
                on_start(func.__name__)

        def on_end(self, ev):
            pass

    with event.install_listener("numba:compile", _Listener()):
        yield
