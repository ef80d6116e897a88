"""``gait batch`` throughput and client memory.

Run from the repository root: ``python benchmarks/bench_batch.py [--copies 20] [--memory-trials 200]``.

1. Throughput: ``--copies`` copies of ``sample_trials/normal`` run by :func:`gaitcli.run.batch.run_batch` with the
   ``muscles_eid`` pipeline (filter, idyn, EID on the right leg; no plots) on a local Dask cluster of 1 and of
   2 worker processes (one thread each). Prints trials per minute for each and the ratio (issue target: at
   least 1.7 on 2 cores), with the cluster's start-up counted in, as a lab would see it.
2. Client memory: ``--memory-trials`` copies run with the filter stage alone on 2 workers; the client's
   resident memory (``VmRSS`` of this process) after every completed trial, printed at 10 %, 50 % and 100 %
   of the trials and as the growth from the first 10 % to the end (flat: the client holds one row per trial
   × stage and two tasks per worker in flight).

Asserts nothing; copies live in a temporary folder.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import time
from pathlib import Path

from gaitcli.resources import sample_trials_dir
from gaitcli.run.batch import run_batch
from gaitcli.run.config import configure


def rss_mb() -> float:
    """This process's resident memory, MB (Linux /proc)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def lab_of(root: Path, copies: int) -> Path:
    lab = root / f"lab{copies}"
    for k in range(copies):
        shutil.copytree(sample_trials_dir() / "normal", lab / f"trial{k:04d}",
                        ignore=shutil.ignore_patterns("gait_out"))
    return lab


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--copies", type=int, default=20)
    parser.add_argument("--memory-trials", type=int, default=200)
    args = parser.parse_args(argv)
    eid = configure(Path("muscles_eid"))
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        rates = {}
        for workers in (1, 2):
            lab = lab_of(root / f"w{workers}", args.copies)
            started = time.perf_counter()
            result = run_batch(lab, eid, workers=workers, plots=False)
            elapsed = time.perf_counter() - started
            rates[workers] = args.copies / elapsed * 60
            print(f"{workers} worker{'s' if workers > 1 else ' '}: {args.copies} trials (filter+idyn+EID) in "
                  f"{elapsed:6.1f} s = {rates[workers]:5.1f} trials/min  [{result.line()}]", flush=True)
        print(f"ratio 2/1 workers: {rates[2] / rates[1]:.2f} (target >= 1.7)")

        lab = lab_of(root / "memory", args.memory_trials)
        samples = []

        def sample(rows):
            if rows and rows[0].stage == "filter":
                samples.append(rss_mb())

        before = rss_mb()
        started = time.perf_counter()
        result = run_batch(lab, _filter_only(), workers=2, plots=False, on_rows=sample)
        elapsed = time.perf_counter() - started
        n = len(samples)
        at = {pct: samples[max(0, int(n * pct / 100) - 1)] for pct in (10, 50, 100)}
        print(f"client memory over {n} trials (filter, 2 workers, {elapsed:.0f} s, {result.line()}): before "
              f"{before:.0f} MB; after 10 % {at[10]:.0f} MB, 50 % {at[50]:.0f} MB, 100 % {at[100]:.0f} MB; "
              f"growth 10 % → 100 %: {at[100] - at[10]:+.1f} MB "
              f"({(at[100] - at[10]) / max(n - n // 10, 1) * 1024:+.1f} kB per trial)")
    return 0


def _filter_only():
    """The standard pipeline with the filter stage alone."""
    import dataclasses

    cfg = configure(None)
    return dataclasses.replace(cfg, stages=("filter",))


if __name__ == "__main__":
    raise SystemExit(main())
