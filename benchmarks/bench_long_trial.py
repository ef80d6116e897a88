"""A trial longer than the C3D header's 65,535 frames through ``gait filter`` and ``gait idyn``.

Run from the repository root: ``python benchmarks/bench_long_trial.py [--strides 833]`` (833 strides of the
synthetic walker: about 100,000 frames at 100 Hz, two plates at 1 kHz). Prints, for ``gait synth``, the C3D reader
alone, ``gait filter`` and ``gait idyn`` (each a new process, one core): wall time, peak resident memory of the
process and of the C3D reader's child, the frame count the stage's summary.json reports against the file's,
and the peak memory per byte of trial.c3d. ``--compare-mb 25 100`` instead prints the peak memory of
``gait compare`` on two identical trees with a joint_moments.csv of about that many MB each (flat in the size:
the tables are read in chunks); ``--ceilings`` prints the documented ceilings. Asserts nothing.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from timing import gait_argv, one_core

_PEAK = ("import resource, subprocess, sys; subprocess.run(sys.argv[1:], check=True, capture_output=True); "
         "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)")


def _run(*args) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of ``gait ARGS`` alone (the largest of it and its children, the C3D
    reader's included), measured by a wrapper process of its own."""
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", _PEAK, *gait_argv(*args)], check=True, capture_output=True,
                         text=True)
    return time.perf_counter() - start, int(out.stdout.split()[-1]) / 1024


def _read(path: Path) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of reading ``path`` with gaitcli's C3D reader in a process of its own."""
    code = ("import resource, sys, warnings; warnings.simplefilter('ignore'); "
            "from gaitcli.io.c3d import read_c3d_here; "
            "read_c3d_here(sys.argv[1]); print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)")
    start = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code, str(path)], check=True, capture_output=True, text=True)
    return time.perf_counter() - start, int(out.stdout.split()[-1]) / 1024


def compare_memory(sizes_mb: list[float]) -> None:
    """Peak memory of ``gait compare`` on two identical trees whose joint_moments.csv is ``size`` MB."""
    print(f"{'CSV MB':>8} {'wall s':>8} {'peak MB':>8}  gait compare A B")
    for size_mb in sizes_mb:
        with tempfile.TemporaryDirectory() as folder:
            rows = int(size_mb * 1e6 / (21 * 11))  # 21 columns of ~11 characters
            table = np.round(np.random.default_rng(0).normal(size=(rows, 21)), 6)
            for side in ("a", "b"):
                path = Path(folder) / side / "trial" / "gait_out" / "idyn" / "joint_moments.csv"
                path.parent.mkdir(parents=True)
                header = "time_s," + ",".join(f"joint{k}_moment" for k in range(20))
                np.savetxt(path, table, fmt="%.6g", delimiter=",", header=header, comments="")
            size = path.stat().st_size
            wall, peak = _run("-q", "compare", Path(folder) / "a", Path(folder) / "b")
            print(f"{size / 1e6:8.0f} {wall:8.1f} {peak:8.0f}")


def ceilings() -> None:
    from gaitcli.io.c3d.header import C3D_MAX_NUMBERS
    from gaitcli.io.h5 import H5_MAX_BYTES
    from gaitcli.run.compare import CHUNK_CELLS

    print(f"C3D data section: {C3D_MAX_NUMBERS} numbers (frames x (4 x markers + analog samples per frame))")
    print(f"HDF5 dataset: {H5_MAX_BYTES} bytes decompressed")
    print(f"gait compare: tables read {CHUNK_CELLS} cells at a time per side")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--strides", type=int, default=833)
    parser.add_argument("--compare-mb", type=float, nargs="+")
    parser.add_argument("--ceilings", action="store_true")
    args = parser.parse_args()
    one_core()
    if args.ceilings:
        return ceilings()
    if args.compare_mb:
        return compare_memory(args.compare_mb)
    with tempfile.TemporaryDirectory() as folder:
        trial = Path(folder) / "long"
        print(f"{'step':<8} {'wall s':>8} {'peak MB':>8}  frames")
        wall, peak = _run("-q", "synth", trial, "--strides", args.strides)
        size = (trial / "trial.c3d").stat().st_size
        print(f"{'synth':<8} {wall:8.1f} {peak:8.0f}  trial.c3d {size / 1e6:.1f} MB")
        wall, peak = _read(trial / "trial.c3d")
        print(f"{'read':<8} {wall:8.1f} {peak:8.0f}  the C3D reader alone; peak {peak * 1e6 / size:.0f} bytes per "
              f"byte of trial.c3d")
        for stage in ("filter", "idyn"):
            wall, peak = _run("-q", stage, trial, "--no-plots")
            summary = json.loads((trial / "gait_out" / stage / "summary.json").read_text())
            frames = summary["frames"]
            print(f"{stage:<8} {wall:8.1f} {peak:8.0f}  {frames} in summary.json; peak "
                  f"{peak * 1e6 / size:.0f} bytes per byte of trial.c3d")


if __name__ == "__main__":
    main()
