"""Functions called in the NLP's expression graph rather than inlined: CasADi then differentiates a function once
for all its calls instead of each instant's copy of its expression (``benchmarks/bench_solver_reuse.py``
measures the solver's construction and its Hessian's instructions)."""

from __future__ import annotations

import casadi as ca


def called(function: ca.Function, *args):
    """``function(*args)`` as one call node of an SX expression graph (not inlined); one output as it is, several
    as a tuple."""
    out = function.call([ca.SX(a) for a in args], False, True)
    return out[0] if len(out) == 1 else tuple(out)


def mapped(function: ca.Function, n: int) -> ca.Function:
    """``function`` evaluated on each of ``n`` column blocks of its inputs, as one function whose call stays one
    node (an SX call of a map would be inlined)."""
    args = [ca.MX.sym(function.name_in(k), function.size1_in(k), function.size2_in(k) * n)
            for k in range(function.n_in())]
    return ca.Function(f"{function.name()}_map", args, function.map(n).call(args))
