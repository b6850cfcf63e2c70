"""Whether the compiled engine still has to be compiled, and a watch on its compiles.

numba compiles a kernel on its first call and caches the machine code (``cache=True``; next to
the package in ``railride/__pycache__``, or in ``NUMBA_CACHE_DIR``). A fresh install has no
cache, so its first closed-loop run compiles the stepper (`railride.kernels.run_batch`), some
ten seconds; later processes load it at once. This module answers, without compiling anything,
whether a kernel is ready (`needs_compiling`), and lets a front end hear when a compile starts
(`watch_compiles`): the command line uses it to say so on stderr; the library itself prints
nothing.
"""

from __future__ import annotations

import contextlib
from typing import Callable, Iterator

#: seconds each kernel takes to compile (docs/performance.md, "Cold start", 2 cores shared
#: with other jobs); the kernels not named compile in about a second and go unannounced
COMPILE_SECONDS = {"run_batch": 10.0}

#: the closed-loop RK4 stepper: MR dampers, ideal devices, controllers
STEPPER = "run_batch"


def _dispatcher(kernel: str):
    from . import kernels

    dispatcher = getattr(kernels, kernel, None)
    if not hasattr(dispatcher, "py_func"):
        names = sorted(n for n, v in vars(kernels).items() if hasattr(v, "py_func") and not n.startswith("_"))
        raise ValueError(f"kernel = {kernel!r}: not a compiled kernel; one of {', '.join(names)}")
    return dispatcher


def needs_compiling(kernel: str = STEPPER) -> bool:
    """Whether the next call of ``kernel`` (a name in `railride.kernels`) compiles it: False when
    this process has compiled or loaded it, or when numba's cache holds machine code for this
    source, this numba and this processor; True otherwise. Compiles nothing."""
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
            if getattr(func, "__module__", "") == "railride.kernels" and func.__name__ in COMPILE_SECONDS:
                on_start(func.__name__)

        def on_end(self, ev):
            pass

    with event.install_listener("numba:compile", _Listener()):
        yield
