"""What the benchmark scripts share: the best wall-clock time of a few repeats (the minimum is
the least disturbed by other work on the machine)."""

import time


def min_time(fn, repeat: int) -> float:
    """The shortest of ``repeat`` wall-clock times of ``fn()`` [s]."""
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best
