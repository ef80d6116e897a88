"""Predictive-gait timings (``gaitcli.predict.nlp``) beside the dissertation's Table 5.1 and two peers.

Run from the repository root: ``python benchmarks/bench_predict.py [--nodes 14 16 18 20] [--iterations N]``.
For each node count: the lifted NLP of normal walking (subject 1, the bundled reference, weights 4/3, 2/3,
1.1275 m/s) built from the default initial guess and solved by IPOPT with exact derivatives
(``solve_windowed``). Prints the build time (the CasADi expressions and the sparsity counts), the
solve's wall time (IPOPT's derivative functions, about 25 s at nn = 18, included) and IPOPT iterations, the exit status, J, Et and Jdev of the last iterate, the
constraint Jacobian's and Lagrangian Hessian's non-zeros, and the ratio to the dissertation's hours.
Threads limited to one, the process to one core. Asserts nothing.

Peers (CHAPTER5_NOTES §5): Moco's example2DWalking prediction, 15 mesh intervals, 1379 s / 412
iterations measured on a 2-core machine of this project's kind; the dissertation 11.3 / 15.9 / 22.3 /
28.9 h at nn = 14 / 16 / 18 / 20 (Table 5.1).
"""

from __future__ import annotations

import argparse
import time

from timing import one_core

import casadi as ca
import numpy as np

from gaitcli.predict.nlp import PredictSettings, build_nlp, initial_guess, instant_segments, solve_windowed
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import read_reference
from gaitcli.resources import bundled_reference

TABLE_5_1_HOURS = {14: 11.3, 16: 15.9, 18: 22.3, 20: 28.9}
MOCO_PREDICTION_S = 1379.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, nargs="+", default=[18])
    parser.add_argument("--iterations", type=int, default=1500)
    args = parser.parse_args()
    one_core()
    reference = read_reference(bundled_reference())
    settings = PredictSettings(max_iterations=args.iterations)
    print(f"{'nn':>3} {'build s':>8} {'solve s':>8} {'iter':>5} {'status':<28} {'J':>7} {'Et J/m':>8} {'Jdev':>6}"
          f" {'jac nnz':>8} {'hess nnz':>8} {'vs Table 5.1':>13} {'vs Moco':>8}")
    for nodes in args.nodes:
        t0 = time.perf_counter()
        transcriber = Transcriber(nodes)
        x0 = initial_guess(transcriber, reference, settings)
        nlp = build_nlp(transcriber, reference, settings, segments=instant_segments(transcriber, x0))
        jac = ca.jacobian(nlp.constraints, nlp.w).nnz()
        hess = ca.hessian(nlp.cost + ca.dot(ca.SX.sym("l", nlp.constraints.size1()), nlp.constraints),
                          nlp.w)[0].nnz()
        build = time.perf_counter() - t0
        t0 = time.perf_counter()
        result = solve_windowed(transcriber, reference, x0, settings)
        wall = time.perf_counter() - t0
        parts = ca.Function("parts", [nlp.w], [nlp.cost, nlp.parts["Et"], nlp.parts["Jdev"]])
        J, et, jdev = (float(v) for v in parts(result["w"]))
        hours = TABLE_5_1_HOURS.get(nodes)
        ratio = f"{hours * 3600 / wall:,.0f}x" if hours else "-"
        print(f"{nodes:>3} {build:8.1f} {wall:8.1f} {result['iterations']:>5} {result['status'][:28]:<28} {J:7.3f}"
              f" {et:8.1f} {jdev:6.2f} {jac:>8} {hess:>8} {ratio:>13} {MOCO_PREDICTION_S / wall:7.2f}x", flush=True)
        np.save(f"/tmp/bench_predict_x_{nodes}.npy", result["x"])


if __name__ == "__main__":
    main()
