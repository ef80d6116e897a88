"""MUMPS's compressed 2×2 ordering (ICNTL(12) = 2) against IPOPT's own MUMPS settings, on the default prediction;
or any benchmark script run with the ordering library (``mumps_ordering.c``, loaded by ``mumps_ordering.py``).

Run from the repository root: ``python benchmarks/bench_mumps_ordering.py --icntl12 {none,0,1,2,3} [--stats]
[--option NAME=VALUE …]``; ``none``: the library not loaded (IPOPT exactly as shipped), 0–3: loaded, each
analysis given that ICNTL(12) (0 leaves MUMPS's default, the library only counting and timing the
factorisations); ``--option``: further IPOPT options of the prediction (e.g. ``ipopt.mumps_scaling=77``).
Prints the default prediction's (``gait predict``'s defaults, ``bench_predict.py``'s construction apart) IPOPT
iterations, the solve's wall seconds, the processor seconds of construction and solve, J, convergence, and where
the library is loaded the number of factorisations and their mean processor and wall time. ``--stats``: IPOPT's
timing statistics and MUMPS's own report (its ``mumps_print_level`` 2) of every analysis and factorisation,
summarised: delayed pivots (INFOG(13)), entries in the factors (INFOG(29)), the largest front (INFOG(11)),
operations (RINFOG(3)), the ICNTL(12) and matching (ICNTL(6)) MUMPS used.

``--run SCRIPT ARG…``: the library loaded with ``--icntl12``'s value, then ``SCRIPT`` run as ``__main__`` with
its arguments (e.g. ``--icntl12 2 --run benchmarks/bench_predict.py --nodes 18``): the other benchmarks with
and without the ordering, unchanged, except that each prediction (``run_predict``) also prints its iterations,
seconds and J to all digits. Processes they fork inherit the library; processes they spawn do not.
One core (``BENCH_CORE``, timing.py); asserts nothing.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import os
import re
import runpy
import statistics
import sys
import tempfile
import time

from timing import one_core, prediction_options

os.environ.setdefault("GFORTRAN_UNBUFFERED_PRECONNECTED", "y")  # MUMPS's reports reach the captured stdout in order

import mumps_ordering  # noqa: E402

FIELDS = {"delays": r"INFOG \(13\) Number of delayed pivots\s+=\s+(\d+)",
          "entries": r"INFOG \(29\) Number of entries in factors\s+=\s+(\d+)",
          "front": r"INFOG \(11\) Maximum front size\s+=\s+(\d+)",
          "operations": r"------ \(3\) Operations in node elimination\s+=\s+([-+.\dD]+)",
          "estimated_entries": r"-- \(20\) Number of entries in factors \(estim.\)\s+=\s+(\d+)",
          "estimated_front": r"--  \(5\) Maximum frontal size      \(estimated\)\s+=\s+(\d+)",
          "icntl12": r"Ordering compressed/constrained \(ICNTL\(12\)\)\s+=\s+(\d+)",
          "ordering": r"--  \(7\) Ordering option effectively used\s+=\s+(\d+)",
          "matching": r"Compute maximum matching \(Maximum Transversal\):\s+(\d+)"}


def load(value: str):
    """The ordering library loaded with ICNTL(12) ``value`` (None for ``none``)."""
    if value == "none":
        return None
    library, why = mumps_ordering.load(int(value))
    if library is None:
        raise SystemExit(f"the ordering library could not be loaded: {why}")
    return library


@dataclasses.dataclass
class CapturedStdout:
    """Everything written to file descriptor 1 (C, Fortran and Python) while in the block, in ``text``."""

    text: str = ""

    def __enter__(self):
        sys.stdout.flush()
        self._file = tempfile.TemporaryFile(mode="w+b")
        self._saved = os.dup(1)
        os.dup2(self._file.fileno(), 1)
        return self

    def __exit__(self, *exc):
        ctypes.CDLL(None).fflush(None)
        os.dup2(self._saved, 1)
        os.close(self._saved)
        self._file.seek(0)
        self.text = self._file.read().decode(errors="replace")
        self._file.close()


def summary(text: str) -> str:
    """MUMPS's reports in ``text`` summarised: each field's first, median and largest value over the reports."""
    out = []
    for name, pattern in FIELDS.items():
        values = [float(v.replace("D", "E")) for v in re.findall(pattern, text)]
        if values:
            out.append(f"{name} {values[0]:.4g} / {statistics.median(values):.4g} / {max(values):.4g} "
                       f"(n={len(values)})")
    timing = [line.strip() for line in text.splitlines()
              if re.match(r"\s*(Overall algorithm|LinearSystemFactorization|LinearSystemSymbolicFactorization|"
                          r"LinearSystemBackSolve|Function evaluations|PDSystemSolverTotal)", line)]
    return "\n".join(["MUMPS (first / median / largest): " + "; ".join(out), *timing])


def default_prediction(stats: bool, options: dict) -> None:
    """The default prediction, its construction apart (``bench_predict.predict``), IPOPT given ``options`` on
    top of the prediction's; ``stats``: MUMPS's reports."""
    import bench_predict

    from gaitcli.predict.stage import PredictConfig

    if stats:
        options = {**options, "ipopt.print_timing_statistics": "yes", "ipopt.print_level": 5,
                   "ipopt.mumps_print_level": 2}
    cfg, tracked, _ = bench_predict.tracking(PredictConfig())
    library = mumps_ordering.loaded()
    before = library.counts() if library else None
    cpu = time.process_time()
    with CapturedStdout() as captured, prediction_options(options):
        run = bench_predict.predict(cfg, tracked)
    cpu = time.process_time() - cpu
    r = run["result"]
    print(f"construct {run['construct_s']:.1f} s; solve {run['solve_s']:.2f} s wall, {cpu:.2f} s CPU (with the "
          f"construction); {r.iterations} iterations in {r.rounds} solves, converged {r.converged}, J {r.objective!r}")
    if library:
        after = library.counts()
        n = after.factorizations - before.factorizations
        print(f"{after.analyses - before.analyses} analyses ({after.analyses_set - before.analyses_set} given "
              f"ICNTL(12)), {n} factorisations, {(after.factorization_cpu_s - before.factorization_cpu_s) / n:.4f}"
              f" s CPU and {(after.factorization_wall_s - before.factorization_wall_s) / n:.4f} s wall each")
    if stats:
        print(summary(captured.text))


def logged_predictions() -> None:
    """Every later ``run_predict`` (imported by name from ``gaitcli.predict.stage`` after this) prints one line:
    speed, model, iterations, convergence, wall and processor seconds and J to all its digits."""
    from gaitcli.predict import stage

    plain = stage.run_predict

    def run_predict(cfg, **kwargs):
        wall, cpu = time.perf_counter(), time.process_time()
        r = plain(cfg, **kwargs)
        print(f"    [run_predict {cfg.speed_m_s} m/s {'symmetric' if cfg.symmetric else 'full'}: {r.iterations} "
              f"iterations, converged {r.converged}, {time.perf_counter() - wall:.2f} s wall, "
              f"{time.process_time() - cpu:.2f} s CPU, J {r.objective!r}]", flush=True)
        return r

    stage.run_predict = run_predict


def option_value(name: str, text: str) -> tuple[str, int | float | str]:
    """(name, value) of one ``--option``: an integer, a number or the text."""
    for kind in (int, float):
        try:
            return name, kind(text)
        except ValueError:
            pass
    return name, text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--icntl12", choices=["none", "0", "1", "2", "3"], default="2")
    parser.add_argument("--stats", action="store_true", help="MUMPS's and IPOPT's own reports, summarised")
    parser.add_argument("--option", nargs="*", default=[], metavar="NAME=VALUE",
                        help="further IPOPT options of the prediction (CasADi's names, e.g. "
                             "ipopt.mumps_permuting_scaling=7), integers or numbers where they parse as such")
    parser.add_argument("--run", nargs=argparse.REMAINDER, metavar="SCRIPT ARG",
                        help="run SCRIPT with its arguments, the library loaded")
    args = parser.parse_args()
    one_core()
    load(args.icntl12)
    if args.run:
        logged_predictions()
        sys.argv = args.run
        sys.path.insert(0, os.path.dirname(os.path.abspath(args.run[0])))
        runpy.run_path(args.run[0], run_name="__main__")
        return
    default_prediction(args.stats, dict(option_value(*a.split("=", 1)) for a in args.option))


if __name__ == "__main__":
    main()
