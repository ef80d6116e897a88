"""How long IPOPT's construction takes for one predictive-gait NLP (``gaitcli.predict.solve.NlpCache.solver``), first
and again with other options.

The first solver of an NLP derives ∇J, the constraint Jacobian and the Hessian of the Lagrangian from the CasADi
expressions; a second one (a warm start's options, another iteration or time limit: every windowed solve's later
rounds on an unmoved window, every chained study case) takes the first one's. Prints, per node count and model,
the NLP's build, the first solver's construction, the second's, their ratio, and the size of the Hessian of the
Lagrangian (non-zeros, instructions, and the time one evaluation takes: what each IPOPT iteration pays).
Run from the repository root: ``python benchmarks/bench_solver_reuse.py [--nodes 6 18] [--model symmetric full]``.
One core (BENCH_CORE: which, benchmarks/timing.py). Asserts nothing.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from timing import one_core

from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout
from gaitcli.predict.nlp import build_nlp, instant_segments
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import read_reference
from gaitcli.predict.settings import PredictSettings
from gaitcli.predict.solve import NlpCache, ipopt_options
from gaitcli.resources import bundled_reference


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, nargs="+", default=[6, 18])
    parser.add_argument("--model", nargs="+", default=["symmetric", "full"], choices=["symmetric", "full"])
    args = parser.parse_args()
    one_core()
    reference = read_reference(bundled_reference())
    settings = PredictSettings()
    for nodes in args.nodes:
        for model in args.model:
            symmetric = model == "symmetric"
            transcriber = Transcriber(nodes)
            x0 = initial_guess(transcriber, reference, symmetric=symmetric)
            began = time.perf_counter()
            nlp = build_nlp(transcriber, reference, symmetric=symmetric,
                            segments=instant_segments(transcriber, DesignLayout.build(nodes, symmetric=symmetric), x0))
            built = time.perf_counter() - began
            cache = NlpCache()
            began = time.perf_counter()
            solver, _ = cache.solver(nlp, ipopt_options(settings, warm=False))
            first = time.perf_counter() - began
            hessian = solver.get_function("nlp_hess_l")
            point = [np.full(nlp.w.numel(), 0.5), settings.parameter_values(), 1.0,
                     np.ones(nlp.constraints.numel())]
            began = time.perf_counter()
            for _ in range(10):
                hessian(*point)
            evaluation_ms = (time.perf_counter() - began) * 100
            began = time.perf_counter()
            cache.solver(nlp, ipopt_options(settings, warm=True))
            second = time.perf_counter() - began
            print(f"nn {nodes:2d} {model:9s}: w {nlp.w.numel():5d}, g {nlp.constraints.numel():5d}; NLP built "
                  f"{built:5.1f} s; first solver {first:5.1f} s, a warm start's {second:4.1f} s "
                  f"({first / second:.0f}× faster); Hessian {hessian.sparsity_out(0).nnz()} non-zeros, "
                  f"{hessian.n_instructions()} instructions, {evaluation_ms:.0f} ms an evaluation", flush=True)


if __name__ == "__main__":
    main()
