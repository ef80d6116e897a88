"""The IPOPT settings of the muscle problems (SO, MSO, EID); the solver itself is ``core/ipopt.py``'s."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca

from gaitcli.core import ipopt
from gaitcli.core.validate import one_of

#: IPOPT's Hessians of the Lagrangian: CasADi's exact one, IPOPT's L-BFGS (``hessian_approximation``), or for
#: EID's metabolic objective its curvature made positive semi-definite, then exact (``hessian.py``)
HESSIANS = ("exact", "limited-memory", "convex")


@dataclass(frozen=True)
class SolverSettings:
    """IPOPT settings shared by SO, MSO and EID.

    ``tol`` IPOPT's relative convergence tolerance, ``constr_viol_tol`` the
    absolute constraint tolerance (constraints are scaled to O(1)),
    ``max_iter`` the iteration limit, ``print_level`` 0–12, ``hessian``
    IPOPT's Hessian of the Lagrangian: ``"exact"`` (CasADi's second
    derivatives), ``"limited-memory"`` (L-BFGS; benchmarks/README.md, "EID's
    growth with its nodes") or ``"convex"`` (EID's metabolic objective: a
    positive semi-definite curvature until IPOPT's steps become small, then
    the exact one; ``hessian.py``; the other problems: exact).
    """

    tol: float = 1e-8
    constr_viol_tol: float = 1e-8
    max_iter: int = 3000
    print_level: int = 0
    hessian: str = "convex"


def build_solver(name: str, x, f, g, p=None, settings: SolverSettings | None = None, *,
                 may_be_infeasible: bool = False, hess_lag: ca.Function | None = None) -> ca.Function:
    """An IPOPT ``nlpsol`` for min f(x, p) s.t. lbg ≤ g(x, p) ≤ ubg, lbx ≤ x ≤ ubx (``settings.hessian``).

    ``may_be_infeasible``: IPOPT's heuristics that detect an infeasible problem sooner (its restoration phase
    entered earlier); on a feasible one they change nothing (benchmarks/README.md, "EID").
    ``hess_lag``: IPOPT's Hessian of the Lagrangian (CasADi's ``nlp_hess_l``: x, p, lam_f, lam_g → upper
    triangle) in place of the exact one.
    """
    s = settings or SolverSettings()
    one_of(s.hessian, HESSIANS, where="hessian")
    problem = {"x": x, "f": f, "g": g, **({"p": p} if p is not None else {})}
    approximation = "limited-memory" if s.hessian == "limited-memory" else "exact"
    opts = ipopt.options(tol=s.tol, max_iter=s.max_iter, print_level=s.print_level,
                         **{"ipopt.constr_viol_tol": s.constr_viol_tol, "ipopt.hessian_approximation": approximation,
                            **({"ipopt.expect_infeasible_problem": "yes"} if may_be_infeasible else {}),
                            **({"hess_lag": hess_lag} if hess_lag is not None else {})})
    return ipopt.build_solver(name, problem, opts)
