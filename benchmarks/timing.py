"""Shared timing helper for the benchmark scripts (run them as `python benchmarks/bench_*.py`)."""

from __future__ import annotations

import statistics
import time


def median_s(func, repeat: int):
    """Median wall time (s) of ``repeat`` calls of ``func`` and the last call's return value."""
    times, value = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        value = func()
        times.append(time.perf_counter() - start)
    return statistics.median(times), value
