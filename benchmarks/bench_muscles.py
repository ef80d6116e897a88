"""Muscle-stage timings on the synthetic walking cycle beside the dissertation's Table 4.2.

Run from the repository root: ``python benchmarks/bench_muscles.py [--repeat N]``.
8 muscles; SO and MSO on every frame of the 100 Hz cycle (110 frames), EID on
50 nodes (400 force variables, as in Table 4.2). Threads are limited to one
core. Prints wall time (best of ``--repeat``), IPOPT iterations, metabolic
cost of one leg and cost of transport, and the speed-up over the
dissertation's fmincon times (subject 1: SO 5.3 s, MSO 7.6 s, EID 4.5e4 s).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from gaitcli.muscles import run_muscles  # noqa: E402
from tests.muscles.conftest import synthetic_gait  # noqa: E402

DISSERTATION = {  # Table 4.2, subject 1: time (s), optimisation variables, metabolic cost (J)
    "so": (5.3, "8 (67x)", None),
    "mso": (7.6, "8 (67x)", 254.8),
    "eid": (4.5e4, "400 (8x50)", 201.0),
}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per method; the fastest is reported")
    parser.add_argument("--nodes", type=int, default=50, help="EID nodes")
    args = parser.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    motion, limb = synthetic_gait()
    print("synthetic gait (tests/muscles/conftest.py): 65 kg, 1.70 m, 1.25 m/s, 1.1 s stride; one core")
    header = (f"{'method':6} {'time (s)':>9} {'Diss. (s)':>10} {'speed-up':>9} {'iter':>6} {'vars':>12} "
              f"{'E (J)':>8} {'Diss. E':>8} {'CoT (J/m)':>10} {'Ralston':>8} {'max |ΔM| (N·m)':>15}")
    print(header)
    print("-" * len(header))
    for method in ("so", "mso", "eid"):
        best, result = float("inf"), None
        for _ in range(args.repeat):
            start = time.perf_counter()
            r = run_muscles(motion, limb, method=method, nodes=args.nodes if method == "eid" else None)
            elapsed = time.perf_counter() - start
            if elapsed < best:
                best, result = elapsed, r
        diss_t, diss_vars, diss_e = DISSERTATION[method]
        vars_ = f"8 ({result.nodes}x)" if method != "eid" else f"{8 * result.nodes} (8x{result.nodes})"
        e = "-" if result.metabolic_cost_J != result.metabolic_cost_J else f"{result.metabolic_cost_J:.1f}"
        cot = "-" if result.cost_of_transport_J_per_m != result.cost_of_transport_J_per_m \
            else f"{result.cost_of_transport_J_per_m:.0f}"
        print(f"{method:6} {best:9.2f} {diss_t:10.3g} {diss_t / best:9.0f} {result.iterations:6d} {vars_:>12} "
              f"{e:>8} {('-' if diss_e is None else f'{diss_e:.1f}'):>8} {cot:>10} {result.ralston_J_per_m:8.0f} "
              f"{result.max_moment_error_Nm:15.2e}"
              + ("" if result.converged else f"  NOT CONVERGED: {result.status}"))
    print(f"(dissertation variables: SO/MSO {DISSERTATION['so'][1]}, EID {DISSERTATION['eid'][1]}; "
          "its CoT for subject 1: 311 J/m vs Ralston 247 J/m)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
