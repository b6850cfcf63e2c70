"""numba's threads shared among batches that step in threads of one process (a study's chunks,
`railride.studies.executors.LocalExecutor`).

A batch steps on as many threads as it has samples (or lane groups) up to numba's thread
count. Two batches that each use every thread, stepping beside each other, share the cores,
end together and then make their rows together while no core steps (docs/performance.md,
"Every core: one batch steps at a time"). So a batch takes the threads it uses before it steps
and waits while they are taken; one that uses fewer steps beside another that leaves room."""

from __future__ import annotations

import contextlib
import threading


class ThreadBudget:
    """The threads of numba's pool that stepping batches hold. `taken(n)` holds n of them (at
    most the calling thread's numba thread count, which is the budget) while its block runs,
    waiting until they are free; a batch alone always runs. A thread that holds some takes none
    again: a progress callback may run a batch itself."""

    def __init__(self) -> None:
        self._free = threading.Condition()
        self._used = 0
        self._held: dict[int, int] = {}  # thread ident -> threads it holds

    @contextlib.contextmanager
    def taken(self, threads: int):
        import numba

        me = threading.get_ident()
        if threads <= 0 or me in self._held:
            yield
            return
        budget = max(1, int(numba.get_num_threads()))
        need = max(1, min(int(threads), budget))
        with self._free:
            while self._used and self._used + need > budget:
                self._free.wait()
            self._used += need
            self._held[me] = need
        try:
            yield
        finally:
            with self._free:
                del self._held[me]
                self._used -= need
                self._free.notify_all()

    @property
    def used(self) -> int:
        """The threads held now."""
        return self._used


#: the process's budget (`railride.run.simulation.run` takes from it for each CPU batch)
CPU_THREADS = ThreadBudget()
