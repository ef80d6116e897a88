"""Static optimization (Diss. 4.1.1): Crowninshield–Brand cost per frame (4.2, 4.3).

All frames are solved in one block-separable NLP (the frames share no
variable, so this equals solving each frame on its own):

    min Σ_j Σ_i (F_ij/PCSA_i)³   s.t.  R_j·F_j = b_j,  0 ≤ F_ij ≤ F_max,i.

Variables are f = F/F_max; since PCSA = F_max/σ, (F/PCSA)³ = σ³f³ and the
minimiser is the same. The upper bound is the maximal isometric force: the
dissertation's SO ignores activation and contraction dynamics, which is why
the activations and excitations its forces need can leave [0, 1] (Fig. 4.7).
The initial guess is zero (Table 4.2).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.core.ipopt import Outcome, solve

from .problem import Problem
from .solver import SolverSettings, build_solver


def moment_constraints(problem: Problem, force):
    """Symbolic (R_j·F_j − b_j) for a CasADi force matrix (m × n), stacked per coordinate (4.21)."""
    rows = []
    for k in range(problem.arms.shape[1]):
        arms_k = ca.DM(problem.arms[:, k, :].T)  # (m, n)
        rows.append(ca.sum1(arms_k * force) - ca.DM(problem.required[:, k]).T)
    return ca.vertcat(*rows)


def solve_so(problem: Problem, settings: SolverSettings | None = None) -> tuple[np.ndarray, Outcome]:
    """Crowninshield–Brand forces (n, m) in N at every node, and the IPOPT outcome."""
    muscle = problem.models.muscle
    m, n = muscle.m, problem.n
    f_max = ca.DM(muscle.params.max_isometric_force_N)
    f = ca.SX.sym("f", m, n)
    force = ca.repmat(f_max, 1, n) * f
    g = ca.vec(moment_constraints(problem, force).T)
    solver = build_solver("so", ca.vec(f), ca.sum1(ca.vec(f ** 3)), g, settings=settings)
    out = solve(solver, x0=np.zeros(m * n), lbx=0.0, ubx=1.0, lbg=0.0, ubg=0.0)
    # IPOPT may end up to its bound relaxation (1e-8 of the bound) below 0
    forces = np.maximum(out.x.reshape(n, m), 0.0) * muscle.params.max_isometric_force_N
    return forces, out
