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

``--scaling [N ...]`` (default 25 50 100 200) prints instead how EID grows with its nodes on that stride: per node
count the NLP's size (variables, constraint-Jacobian and Hessian non-zeros), the whole ``solve_eid`` call
(construction and solve; wall and CPU seconds), IPOPT's iterations, solve seconds (``Outcome.time_s``) and
milliseconds per iteration, the optimiser's J and the forces' RMS difference to the next coarser count's
(interpolated); then the least-squares exponent of solve seconds (and of iterations) against nodes.
``--hessian limited-memory`` runs the same with IPOPT's L-BFGS Hessian, ``--hessian convex`` with the objective's
curvature made positive semi-definite, then exact (``gaitcli/muscles/hessian.py``).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import median_s, one_core, sample_legs, solver_libraries

from gaitcli.muscles.solver import HESSIANS, SolverSettings
from gaitcli.muscles.stage import run_muscles

SCALING_NODES = (25, 50, 100, 200)

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
    parser.add_argument("--scaling", type=int, nargs="*", help=f"EID's growth with its nodes (default "
                        f"{' '.join(map(str, SCALING_NODES))}) instead of the table")
    parser.add_argument("--hessian", choices=HESSIANS, default=SolverSettings().hessian,
                        help="IPOPT's Hessian for --scaling")
    args = parser.parse_args(argv)
    one_core()
    with tempfile.TemporaryDirectory(prefix="bench_muscles_") as tmp:
        subject, legs = sample_legs(Path(tmp), args.side, ("cycle", "swing"), sample=args.sample)
    cycle = legs["cycle"]
    if args.scaling is not None:
        status = eid_scaling(cycle, tuple(args.scaling) or SCALING_NODES, args.hessian)
        print(solver_libraries())
        return status
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


def eid_scaling(leg, node_counts, hessian: str) -> int:
    """Print EID's size, iterations and times per node count on ``leg``'s interval, and the fitted exponents."""
    import casadi as ca
    import numpy as np

    from gaitcli.muscles import eid
    from gaitcli.muscles.problem import Models, build_problem
    from gaitcli.muscles.so import solve_so
    from gaitcli.muscles.solver import SolverSettings

    models = Models.build(leg.limb)
    print(f"EID scaling on {leg.interval_s[0]:.2f}–{leg.interval_s[1]:.2f} s ({'' if leg.periodic else 'not '}periodic)"
          f", metabolic objective, {hessian} Hessian")
    header = (f"{'nodes':>5} {'vars':>6} {'jac nnz':>8} {'hess nnz':>9} {'total s':>8} {'cpu s':>7} {'iter':>5} "
              f"{'solve s':>8} {'ms/iter':>8} {'J (J)':>9} {'ΔF RMS (N)':>11}  status")
    print(header)
    print("-" * len(header))
    rows, previous = [], None
    for n in node_counts:
        problem = build_problem(leg.motion, models, nodes=n, interval=leg.interval_s, periodic=leg.periodic)
        so = solve_so(problem)
        x, cost, g = eid._eid_nlp(problem, "metabolic", 1e-2, None)
        jac_nnz = ca.jacobian(g, x).nnz()
        hess_nnz = ca.triu(ca.hessian(cost + ca.dot(ca.SX.sym("lam", g.shape[0]), g), x)[0]).nnz()
        wall, cpu = time.perf_counter(), time.process_time()
        solution = eid.solve_eid(problem, SolverSettings(hessian=hessian), warm_start=so)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        out, force = solution.outcome, solution.force_N
        diff = "-"
        if previous is not None:  # the coarser solution, periodic-linearly interpolated onto these nodes
            t_prev, f_prev, period = previous
            coarse = np.array([np.interp(problem.time_s, t_prev, f_prev[:, i], period=period)
                               for i in range(force.shape[1])]).T
            diff = f"{np.sqrt(np.mean((coarse - force) ** 2)):.1f}"
        previous = (problem.time_s, force, problem.t_end_s - problem.t_start_s)
        rows.append((n, out.iterations, out.time_s))
        print(f"{n:5d} {x.shape[0]:6d} {jac_nnz:8d} {hess_nnz:9d} {wall:8.2f} {cpu:7.2f} {out.iterations:5d} "
              f"{out.time_s:8.2f} {1e3 * out.time_s / max(out.iterations, 1):8.2f} {out.objective:9.3f} {diff:>11}  "
              f"{out.status}", flush=True)
    nodes, iters, secs = (np.array(c, float) for c in zip(*rows))
    if nodes.size > 1:
        slope = {name: np.polyfit(np.log(nodes), np.log(v), 1)[0] for name, v in (("solve", secs), ("iter", iters))}
        print(f"exponent (least squares on log-log): solve s ∝ nodes^{slope['solve']:.2f}, "
              f"iterations ∝ nodes^{slope['iter']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
