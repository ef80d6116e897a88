"""IPOPT (bundled with CasADi) with exact derivatives: building and running NLP solvers."""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.core.interrupts import interrupts_raised


@dataclass(frozen=True)
class SolverSettings:
    """IPOPT settings shared by SO, MSO and EID.

    ``tol`` IPOPT's relative convergence tolerance, ``constr_viol_tol`` the
    absolute constraint tolerance (constraints are scaled to O(1)),
    ``max_iter`` the iteration limit, ``print_level`` 0–12.
    """

    tol: float = 1e-8
    constr_viol_tol: float = 1e-8
    max_iter: int = 3000
    print_level: int = 0


@dataclass(frozen=True)
class Outcome:
    """Solution and IPOPT's own report."""

    x: np.ndarray
    objective: float
    success: bool
    status: str
    iterations: int
    time_s: float


def build_solver(name: str, x, f, g, p=None, settings: SolverSettings | None = None) -> ca.Function:
    """An IPOPT ``nlpsol`` for min f(x, p) s.t. lbg ≤ g(x, p) ≤ ubg, lbx ≤ x ≤ ubx."""
    s = settings or SolverSettings()
    nlp = {"x": x, "f": f, "g": g}
    if p is not None:
        nlp["p"] = p
    opts = {"print_time": False, "ipopt.print_level": s.print_level, "ipopt.sb": "yes",
            "ipopt.tol": s.tol, "ipopt.constr_viol_tol": s.constr_viol_tol,
            "ipopt.max_iter": s.max_iter, "ipopt.mu_strategy": "adaptive",
            "ipopt.hessian_approximation": "exact"}
    return ca.nlpsol(name, "ipopt", nlp, opts)


def solve(solver: ca.Function, x0, lbx, ubx, lbg, ubg, p=None) -> Outcome:
    """Run ``solver`` and collect the solution, status and iteration count."""
    args = {"x0": x0, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
    if p is not None:
        args["p"] = p
    start = time.perf_counter()
    with interrupts_raised():  # an interrupted solve is no result (core/interrupts.py)
        sol = solver(**args)
    elapsed = time.perf_counter() - start
    stats = solver.stats()
    return Outcome(x=np.array(sol["x"]).ravel(), objective=float(sol["f"]),
                   success=bool(stats.get("success", False)), status=str(stats.get("return_status", "")),
                   iterations=int(stats.get("iter_count", -1)), time_s=elapsed)
