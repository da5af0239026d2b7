"""Shared timing helper of the benchmark scripts in this folder: they import it as ``timing``
(``from timing import first_and_warm``), which needs no sys.path edit because
``python benchmarks/<script>.py`` puts the script's own folder first on sys.path."""
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


def first_and_warm(fn, repeats):
    """(wall time of the first call — compilation included —, median of ``repeats`` warm calls;
    nan when repeats is 0)."""
    t0 = time.perf_counter()
    fn()
    first = time.perf_counter() - t0
    return first, median_time(fn, repeats) if repeats > 0 else float("nan")
