"""Predictive-gait timings (``gaitcli.predict.nlp``, ``gaitcli.predict.solve``) beside the dissertation's Table 5.1
and two peers.

Run from the repository root: ``python benchmarks/bench_predict.py [--nodes 14 16 18 20] [--iterations N]
[--model symmetric full]``. For each node count and model: ``run_predict`` on normal walking (subject 1,
the bundled reference, weights 4/3, 2/3, 1.1275 m/s) from the default initial guess (the full model: from the
symmetric model's solution, whose solve its figures include): the lifted NLP solved
by IPOPT with exact derivatives, its windows moved and re-solved while they bind (``solve_windowed``).
Prints the build time (the CasADi expressions and the sparsity counts), the whole call's wall time
(IPOPT's derivative functions included) with its IPOPT iterations and solves, the exit status, J, Et and Jdev
of the last iterate, the constraint Jacobian's and Lagrangian Hessian's non-zeros, and the ratio to the
dissertation's hours.
Threads limited to one, the process to one core. Asserts nothing.

Peers: Moco's example2DWalking prediction, 15 mesh intervals, 1379 s / 412
iterations measured on a 2-core machine of this project's kind; the dissertation 11.3 / 15.9 / 22.3 /
28.9 h at nn = 14 / 16 / 18 / 20 (Table 5.1).
"""

from __future__ import annotations

import argparse
import time

import casadi as ca
from timing import one_core

from gaitcli.predict.nlp import build_nlp
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import read_reference
from gaitcli.predict.stage import PredictConfig, run_predict
from gaitcli.resources import bundled_reference

TABLE_5_1_HOURS = {14: 11.3, 16: 15.9, 18: 22.3, 20: 28.9}
MOCO_PREDICTION_S = 1379.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, nargs="+", default=[14, 16, 18, 20])
    parser.add_argument("--model", nargs="+", default=["symmetric", "full"], choices=["symmetric", "full"])
    parser.add_argument("--iterations", type=int, default=3000)
    args = parser.parse_args()
    one_core()
    reference = read_reference(bundled_reference())
    print(f"{'nn':>3} {'model':<9} {'build s':>7} {'total s':>8} {'iter':>5} {'solves':>6} {'conv':>5} {'J':>7}"
          f" {'Et J/m':>7} {'Jdev':>6} {'jac nnz':>8} {'hess nnz':>8} {'vs Table 5.1':>12} {'vs Moco':>8}")
    for nodes in args.nodes:
        for model in args.model:
            symmetric = model == "symmetric"
            t0 = time.perf_counter()
            transcriber = Transcriber(nodes)
            nlp = build_nlp(transcriber, reference, symmetric=symmetric)
            lam = ca.SX.sym("l", nlp.constraints.size1())
            jac = ca.jacobian(nlp.constraints, nlp.w).nnz()
            hess = ca.hessian(nlp.cost + ca.dot(lam, nlp.constraints), nlp.w)[0].nnz()
            build = time.perf_counter() - t0
            cfg = PredictConfig(nodes=nodes, symmetric=symmetric, max_iterations=args.iterations)
            t0 = time.perf_counter()
            result = run_predict(cfg, reference=reference)
            wall = time.perf_counter() - t0
            hours = TABLE_5_1_HOURS.get(nodes)
            ratio = f"{hours * 3600 / wall:,.0f}x" if hours else "-"
            print(f"{nodes:>3} {model:<9} {build:7.1f} {wall:8.1f} {result.iterations:>5} {result.rounds:>6}"
                  f" {str(result.converged):>5} {result.objective:7.3f} {result.cost_of_transport_J_per_m:7.1f}"
                  f" {result.deviation:6.2f} {jac:>8} {hess:>8} {ratio:>12} {MOCO_PREDICTION_S / wall:7.2f}x",
                  flush=True)
            checks = result.gait_checks()
            print("    gait checks: " + ", ".join(f"{k} {v['value']} {'ok' if v['ok'] else 'FAILS'}"
                                                  for k, v in checks.items()), flush=True)


if __name__ == "__main__":
    main()
