"""What the benchmark scripts share: the best wall-clock time of a few repeats (the minimum is
the least disturbed by other work on the machine), and the time covered by (start, end)
intervals recorded in several threads."""

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


def covered(intervals) -> float:
    """The length of the union of (start, end) intervals [s]: the time at least one was open."""
    total, end = 0.0, float("-inf")
    for a, b in sorted(intervals):
        if b <= end:
            continue
        total += b - max(a, end)
        end = b
    return total


def clipped(intervals, spans) -> list:
    """The parts of (start, end) ``intervals`` that lie within any of ``spans``."""
    return [(max(a, c), min(b, d)) for a, b in intervals for c, d in spans if b > c and a < d]
