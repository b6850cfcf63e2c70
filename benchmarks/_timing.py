"""What the benchmark scripts share: the best wall-clock time of a few repeats (the minimum is
the least disturbed by other work on the machine)."""

import time


def min_time(fn, repeat: int, clock=time.perf_counter) -> float:
    """The shortest of ``repeat`` times of ``fn()`` [s] on ``clock``: wall-clock by default;
    ``time.process_time`` for the CPU time of all the process's threads."""
    best = float("inf")
    for _ in range(repeat):
        t0 = clock()
        fn()
        best = min(best, clock() - t0)
    return best
