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


class QuietConsole:
    """Stand-in for the CLI console when a benchmark drives ``gaitcli.pipeline.Run``: no messages, no bars."""

    quiet, as_json = True, False

    def info(self, message):
        pass

    def summary(self, stage, summary, out_dir):
        pass

    def progress(self, description, total=None):
        from gaitcli.report.progress import progress_bar

        return progress_bar(description, total=total, enabled=False)
