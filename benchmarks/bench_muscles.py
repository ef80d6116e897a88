"""Muscle-stage timings on the bundled normal sample trial beside the dissertation's Table 4.2.

Run from the repository root: ``python benchmarks/bench_muscles.py [--repeat N] [--side r|l] [--sample NAME]``
(``--sample ski_boot``: a trial whose moments the muscles cannot make, EID infeasible).
The filter and idyn stages run once on a copy of ``sample_trials/normal`` (55 kg, 1.65 m,
0.88 m/s) and the leg is read back from idyn.h5 (``stage("idyn").read``, ``prepare_leg``); then, on
the first stride whose stance is on a plate (periodic, 4.3.5), with the 8 muscles of Table A.1: SO
and MSO on every 100 Hz frame of the stride (as Table 4.2 solves one small problem per frame) and
on the 50 EID nodes ("so 50", "mso 50"), EID on 50 nodes (400 force variables, as Table 4.2), and
EID on the swing phase with the forward validation of 4.5.4. Threads are limited to one and the process
to one core. Prints median wall time of ``--repeat`` runs (the whole ``run_muscles`` call: model
set-up, NLP construction, solve, inversions, energetics), IPOPT iterations, metabolic cost of one
leg, cost of transport (both legs) beside Ralston's (4.5), the largest moment-equation error, and
the speed-up over the dissertation's times (subject 1: SO 5.3 s, MSO 7.6 s, EID 4.5e4 s).
Asserts nothing. (The whole ``gait muscles`` command, end to end: ``benchmarks/bench_cli.py``.)
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import median_s, one_core, sample_legs

from gaitcli.muscles.stage import run_muscles

DISSERTATION = {  # Table 4.2, subject 1: time (s), optimisation variables, metabolic cost (J)
    "so": (5.3, "8 (67x)", None),
    "mso": (7.6, "8 (67x)", 254.8),
    "eid": (4.5e4, "400 (8x50)", 201.0),
}


def _fmt(x, spec):
    return "-" if x != x else format(x, spec)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=3, help="runs per method; the median is reported")
    parser.add_argument("--side", choices=("r", "l"), default="r")
    parser.add_argument("--nodes", type=int, default=50, help="EID nodes")
    parser.add_argument("--sample", default="normal", help="the bundled sample trial (default normal)")
    args = parser.parse_args(argv)
    one_core()
    with tempfile.TemporaryDirectory(prefix="bench_muscles_") as tmp:
        subject, legs = sample_legs(Path(tmp), args.side, ("cycle", "swing"), sample=args.sample)
    cycle = legs["cycle"]
    start, end = cycle.interval_s
    print(f"sample_trials/{args.sample} ({subject.mass_kg:g} kg, {subject.stature_m:g} m), side {args.side}, stride "
          f"{start:.2f}–{end:.2f} s; one core, median of {args.repeat}")
    header = (f"{'method':10} {'time (s)':>9} {'Diss. (s)':>10} {'speed-up':>9} {'iter':>6} {'vars':>12} "
              f"{'E (J)':>8} {'Diss. E':>8} {'CoT (J/m)':>10} {'Ralston':>8} {'max |ΔM| (N·m)':>15}")
    print(header)
    print("-" * len(header))
    rows = [("so", "cycle", None, False), ("mso", "cycle", None, False),
            ("so", "cycle", args.nodes, False), ("mso", "cycle", args.nodes, False),
            ("eid", "cycle", args.nodes, False), ("eid", "swing", args.nodes, True)]
    for method, phase, nodes, validate in rows:
        leg = legs[phase]

        def solve(leg=leg, method=method, nodes=nodes, validate=validate):
            return run_muscles(leg.motion, leg.limb, method=method, nodes=nodes, interval=leg.interval_s,
                               periodic=leg.periodic, validate=validate)

        seconds, result = median_s(solve, args.repeat)
        diss_t, diss_vars, diss_e = DISSERTATION[method]
        label = (method if nodes is None or method == "eid" else f"{method} {nodes}") + \
            ("" if phase == "cycle" else " swing")
        vars_ = f"8 ({result.nodes}x)" if method != "eid" else f"{8 * result.nodes} (8x{result.nodes})"
        diss = f"{diss_t:10.3g} {diss_t / seconds:9.0f}" if phase == "cycle" else f"{'-':>10} {'-':>9}"
        print(f"{label:10} {seconds:9.2f} {diss} "
              f"{result.iterations:6d} {vars_:>12} {_fmt(result.metabolic_cost_J, '.1f'):>8} "
              f"{('-' if diss_e is None or phase != 'cycle' else f'{diss_e:.1f}'):>8} "
              f"{_fmt(result.cost_of_transport_J_per_m, '.0f'):>10} {result.ralston_J_per_m:8.0f} "
              f"{result.max_moment_error_Nm:15.2e}"
              + ("" if result.converged else f"  NOT CONVERGED: {result.status}"))
        if validate:
            v = result.validation
            print(f"{'':10} forward validation (4.5.4): joint angles {v.rms_total_deg:.2f}° RMS, metabolic cost "
                  f"{v.metabolic_cost_forward_J:.1f} J vs EID {result.metabolic_cost_J:.1f} J "
                  f"(dissertation, subject 1 swing: 44.3 J vs 46.1 J)")
    print(f"(dissertation variables: SO/MSO {DISSERTATION['so'][1]}, EID {DISSERTATION['eid'][1]}; "
          "its CoT for subject 1: 311 J/m vs Ralston 247 J/m)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
