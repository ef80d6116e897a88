"""End to end: ``gait muscles --method eid`` on the normal sample trial, and where its time goes.

Run from the repository root: ``python benchmarks/bench_cli.py [--repeat N]``.

A copy of ``sample_trials/normal`` is made and ``gait idyn`` run on it once, so that its filter and idyn
outputs are up to date (``gait muscles`` reads them back instead of recomputing them; checked: idyn.h5
is not rewritten). Then ``gait muscles --method eid COPY`` is timed in a new process each time (the
console script beside this Python), with and without ``--no-plots``: the median of ``--repeat``
(default 3) runs, one core, ``OMP_NUM_THREADS=1``, beside the issue's target of 4 s end to end (the
ratio measured / target; nothing is asserted).

The breakdown is measured in-process, in a new process per run as well (this script run with
``--child``; medians of ``--repeat``): Python's start-up (``python -c pass``); the imports the command
makes (``gaitcli.cli`` first, then what is imported on first use: ``gaitcli.run.pipeline``, the muscle
writer and, with figures, ``gaitcli.report.plots`` with matplotlib); then one
``run_stages(copy, ["muscles"], cfg, plots=...)`` — what the command calls — with timing wrappers
put around the functions it goes through (benchmark-side only; gaitcli is not edited): hashing the
input files, the freshness checks, reading filter.h5 and idyn.h5 back, the EID stage
(``run_muscles_stage``: model and problem set-up, the SO warm start, the EID NLP's CasADi expressions,
the IPOPT solver's construction — ``muscles.solver.build_solver`` — and the IPOPT solve —
``core.ipopt.solve`` —, and the rest: inversions, energetics, result), the CSV tables, muscles.h5
and summary.json, and each figure (from the previous figure's end, or the figure function's start,
to the end of its PNG; the first includes reading muscles.h5). "Rest" rows are what the wrapped
calls leave of their parent; "click, printing, exit" is end-to-end minus start-up, imports and
``run_stages``. Last, the heaviest packages among those imports (``python -X importtime``,
cumulative).
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from importlib import import_module
from pathlib import Path

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import Stopwatch, copy_sample, figure_times, median_of, one_core, python_s, run_gait, time_gait

TARGET_S = 4.0
COMMAND = ("muscles", "--method", "eid")
#: what ``gait muscles`` imports, in order: the CLI, then on first use the pipeline, the writer, the figures
MODULES = ("gaitcli.cli", "gaitcli.run.pipeline", "gaitcli.muscles.outputs")
PLOTS_MODULE = "gaitcli.report.plots"

#: breakdown rows: (label, depth); the order in which they are printed
STAGE_ROWS = [
    ("hash input files", 1), ("freshness checks", 1), ("read filter.h5", 1), ("read idyn.h5", 1),
    ("EID stage (run_muscles_stage)", 1),
    ("models (muscles, limb, joints)", 2), ("problem (nodes, arms, ID moments)", 2),
    ("SO warm start", 2), ("SO: IPOPT construction", 3), ("SO: IPOPT solve", 3), ("SO: rest", 3),
    ("EID: NLP expressions (CasADi SX)", 2), ("EID: IPOPT construction", 2), ("EID: IPOPT solve", 2),
    ("EID stage: rest", 2),
    ("write CSV tables", 1), ("muscles.h5: datasets", 1), ("muscles.h5: write", 1), ("summary.json", 1),
    ("figures", 1),
]


def child(folder: Path, plots: bool) -> dict:
    """One ``gait muscles --method eid`` as the CLI runs it, timed part by part (in a fresh process)."""
    imports = {}
    for module in MODULES + ((PLOTS_MODULE,) if plots else ()):
        start = time.perf_counter()
        import_module(module)
        imports[f"import {module}"] = time.perf_counter() - start

    from gaitcli.muscles import eid, so
    from gaitcli.muscles import outputs as muscles_outputs
    from gaitcli.muscles import stage as muscle_stage
    from gaitcli.run import pipeline, stages
    from gaitcli.run.config import configure

    figures = {}
    with Stopwatch() as w:
        w.wrap(pipeline, "sha256", "hash input files")
        w.wrap(pipeline.TrialRun, "fresh", "freshness checks")
        w.wrap(stages, "read_result", lambda path, *a, **k: f"read {Path(path).name}")
        w.wrap(stages, "run_muscles_stage", "EID stage (run_muscles_stage)")
        w.wrap(muscle_stage.Models, "build", "models (muscles, limb, joints)")
        w.wrap(muscle_stage, "build_problem", "problem (nodes, arms, ID moments)")
        w.wrap(eid, "solve_so", "SO warm start")
        w.wrap(so, "build_solver", "SO: IPOPT construction")
        w.wrap(so, "solve", "SO: IPOPT solve")
        w.wrap(eid, "_eid_nlp", "EID: NLP expressions (CasADi SX)")
        w.wrap(eid, "build_solver", "EID: IPOPT construction")
        w.wrap(eid, "solve", "EID: IPOPT solve")
        w.wrap(muscles_outputs, "write_table", "write CSV tables")
        w.wrap(muscles_outputs, "record_datasets", "muscles.h5: datasets")
        w.wrap(muscles_outputs, "write_h5", "muscles.h5: write")
        w.wrap(pipeline, "write_json", "summary.json")
        if plots:
            plotting = import_module(PLOTS_MODULE)
            drawn = plotting.muscle_figures

            def muscle_figures(h5_path, folder, *, title=""):
                figures.update(figure_times(drawn, h5_path, folder, title))

            plotting.muscle_figures = muscle_figures
            w.wrap(plotting, "muscle_figures", "figures")
        cfg = configure(None, muscles={"method": "eid"})
        start = time.perf_counter()
        outcomes = pipeline.run_stages(folder, ["muscles"], cfg, plots=plots)
        total = time.perf_counter() - start
    s = w.seconds
    parts = {label: s.get(label, 0.0) for label, _ in STAGE_ROWS}
    parts["SO: rest"] = parts["SO warm start"] - parts["SO: IPOPT construction"] - parts["SO: IPOPT solve"]
    parts["EID stage: rest"] = parts["EID stage (run_muscles_stage)"] - sum(
        parts[k] for k in ("models (muscles, limb, joints)", "problem (nodes, arms, ID moments)", "SO warm start",
                           "EID: NLP expressions (CasADi SX)", "EID: IPOPT construction", "EID: IPOPT solve"))
    parts["rest of run_stages"] = total - sum(parts[label] for label, depth in STAGE_ROWS if depth == 1)
    muscles = next(o for o in outcomes if o.stage == "muscles")
    return {"imports": imports, "parts": parts, "figures": {k: v[0] for k, v in figures.items()},
            "saving": {k: v[1] for k, v in figures.items()}, "run_stages": total,
            "statuses": {o.stage: o.status for o in outcomes},
            "cost_J": muscles.summary.get("metabolic_cost_J"), "iterations": muscles.summary.get("iterations")}


def breakdown(folder: Path, plots: bool, repeat: int) -> dict:
    """Medians over ``repeat`` fresh processes of :func:`child`."""
    runs = []
    for _ in range(max(1, repeat)):
        argv = [sys.executable, __file__, "--child", str(folder)] + ([] if plots else ["--no-plots"])
        out = subprocess.run(argv, check=True, capture_output=True, text=True).stdout
        runs.append(json.loads(out.strip().splitlines()[-1]))
    merged = {key: median_of([r[key] for r in runs]) for key in ("imports", "parts", "figures", "saving")
              if runs[0][key]}
    merged["run_stages"] = statistics.median(r["run_stages"] for r in runs)
    for key in ("statuses", "cost_J", "iterations"):
        merged[key] = runs[-1][key]
    return merged


def heaviest_imports(limit_ms: float = 30.0) -> list[tuple[str, float]]:
    """Top-level packages whose imports took over ``limit_ms`` (``-X importtime``), heaviest first.

    A package's time is the cumulative time of its modules imported from outside it (what they
    import first from other packages included).
    """
    code = "; ".join(f"import {m}" for m in MODULES + (PLOTS_MODULE,))
    err = subprocess.run([sys.executable, "-X", "importtime", "-c", code], check=True, capture_output=True,
                         text=True).stderr
    lines = []
    for line in err.splitlines():
        fields = line[len("import time:"):].split("|") if line.startswith("import time:") else []
        if len(fields) == 3 and fields[1].strip().isdigit():
            name = fields[2][1:]  # one space after the bar, then two per level of nesting
            lines.append(((len(name) - len(name.lstrip())) // 2, name.strip().split(".")[0], int(fields[1]) / 1e3))
    packages, stack = {}, []
    for depth, top, ms in reversed(lines):  # a module's line follows those it imported: parents first here
        while stack and stack[-1][0] >= depth:
            stack.pop()
        if not stack or stack[-1][1] != top:
            packages[top] = packages.get(top, 0.0) + ms
        stack.append((depth, top))
    return sorted(((k, v) for k, v in packages.items() if v > limit_ms), key=lambda kv: -kv[1])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing; the median is reported")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--no-plots", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child is not None:
        print(json.dumps(child(args.child, not args.no_plots)))
        return 0
    one_core()
    with tempfile.TemporaryDirectory(prefix="bench_cli_") as tmp:
        folder = copy_sample("normal", Path(tmp) / "normal")
        run_gait("-q", "idyn", folder)
        idyn_h5 = folder / "gait_out" / "idyn" / "idyn.h5"
        stamp = idyn_h5.stat().st_mtime_ns
        end_to_end = {plots: time_gait(*COMMAND, *([] if plots else ["--no-plots"]), folder, repeat=args.repeat)
                      for plots in (True, False)}
        parts = {plots: breakdown(folder, plots, args.repeat) for plots in (True, False)}
        reused = idyn_h5.stat().st_mtime_ns == stamp
    startup = python_s("pass", args.repeat)

    with_plots, no_plots = parts[True], parts[False]
    print(f"`gait {' '.join(COMMAND)}` on a copy of sample_trials/normal whose filter and idyn outputs are up "
          f"to date ({'reused, idyn.h5 not rewritten' if reused else 'NOT reused: idyn.h5 was rewritten'}); "
          f"new process each time, median of {args.repeat}, one core, OMP_NUM_THREADS=1")
    print(f"EID: metabolic cost {with_plots['cost_J']:.3f} J, {with_plots['iterations']} IPOPT iterations; "
          f"stages: {', '.join(f'{k} {v}' for k, v in with_plots['statuses'].items())}")
    print(f"\n{'':28} {'end to end (s)':>15} {'target (s)':>11} {'ratio':>6}")
    for plots, label in ((True, "with figures"), (False, "--no-plots")):
        print(f"{label:28} {end_to_end[plots]:15.2f} {TARGET_S:11.1f} {end_to_end[plots] / TARGET_S:6.2f}")

    print(f"\nwhere the time goes, s (in-process, a new process per run, median of {args.repeat}):")
    print(f"{'':44} {'figures':>8} {'--no-plots':>10}")

    def fmt(x):
        return "-" if x is None else f"{x:.3f}"

    def row(label, a, b, depth=0):
        print(f"{'  ' * depth + label:44} {fmt(a):>8} {fmt(b):>10}")

    row("python start-up (python -c pass)", startup, startup)
    for key in with_plots["imports"]:
        row(key, with_plots["imports"][key], no_plots["imports"].get(key))
    row("run_stages(['muscles'], plots=...)", with_plots["run_stages"], no_plots["run_stages"])
    for label, depth in STAGE_ROWS + [("rest of run_stages", 1)]:
        row(label, with_plots["parts"][label], None if label == "figures" else no_plots["parts"][label], depth)
        if label == "figures":
            for name, seconds in with_plots["figures"].items():
                row(f"{name} (saving PNG {with_plots['saving'][name]:.3f})", seconds, None, 2)
    for plots in (True, False):
        p = parts[plots]
        p["accounted"] = startup + sum(p["imports"].values()) + p["run_stages"]
    row("click, printing, exit (end to end − above)", end_to_end[True] - with_plots["accounted"],
        end_to_end[False] - no_plots["accounted"])
    row("end to end", end_to_end[True], end_to_end[False])
    heavy = dict(heaviest_imports())
    total = heavy.pop("gaitcli", float("nan"))
    print(f"\nthose imports under python -X importtime (one process): {total:.0f} ms in all; the heaviest "
          "packages (cumulative, ms): " + ", ".join(f"{name} {ms:.0f}" for name, ms in heavy.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
