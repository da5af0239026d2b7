"""Shared timing helper of the benchmark scripts."""
import statistics
import time


def median_time(fn, repeats):
    """Median wall time (s) of ``repeats`` calls of fn (the machines are shared and noisy)."""
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)
