"""Extended inverse dynamics (Diss. 4.3, (4.6)–(4.29)).

One NLP over all muscles × nodes: find the nodal muscle forces that minimise
the total metabolic cost (4.29) (or the Crowninshield–Brand cost) subject to
the moment equations at every node (4.20–4.25), 0 ≤ u ≤ 1 (4.26),
0 ≤ a ≤ 1 (4.27) and 0 ≤ F ≤ f_asympt·F_max (4.28). Forces are inverted to
activations and excitations with central differences (4.10) — periodic for a
full cycle (one time step between the last and the first node, 4.5.2) —
or, for a non-periodic interval, with extra nodes before and after (4.3.6)
and one-sided differences at the outermost nodes (4.11, 4.12).

Variable layout (all m × n, stored column by column, i.e. node-major): the
normalised tendon stretch ŝ (F = F_max·ŝ², a one-to-one reparameterisation of
the force that keeps the tendon inversion (4.13) smooth at F = 0), the
activation a and the excitation u. a and u are the values the explicit
inversion chain (4.13–4.19) would compute from F; they are carried as
variables tied by the contraction equation (4.18) and the activation dynamics
(2.17), whose unique root in [0, 1] is the root rule's choice (4.3.3). This
lifting gives IPOPT exact, sparse first and second derivatives of a
polynomial-like problem instead of nested square roots and divisions.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .hill import finite_difference_matrix
from .mso import MOMENT_SCALE_NM
from .problem import Problem
from .so import moment_constraints, solve_so
from .solver import Outcome, SolverSettings, build_solver, solve

OBJECTIVES = ("metabolic", "crowninshield_brand")


@dataclass(frozen=True)
class EidSolution:
    """Forces, activations and excitations (n, m) at all nodes (extra nodes included)."""

    force_N: np.ndarray
    activation: np.ndarray
    excitation: np.ndarray
    outcome: Outcome
    warm_start_outcome: Outcome
    node_weights: np.ndarray  # (n,) quadrature weights of the objective, in units of Δt


def quadrature_weights(n: int, periodic: bool) -> np.ndarray:
    """Weights w_j of ∫ y dt ≈ Δt·Σ w_j y_j: rectangle rule on a periodic grid, trapezoid otherwise."""
    w = np.ones(n)
    if not periodic:
        w[0] = w[-1] = 0.5
    return w


def solve_eid(problem: Problem, settings: SolverSettings | None = None, *, objective: str = "metabolic",
              warm_start: tuple[np.ndarray, Outcome] | None = None, smoothing: float = 1e-2) -> EidSolution:
    """Solve the EID NLP on the nodes of ``problem``, warm-started from SO (Table 4.2).

    ``warm_start`` = (SO forces (n, m), SO outcome) on the same nodes; computed when omitted.
    """
    if objective not in OBJECTIVES:
        raise ValueError(f"objective {objective!r} not in {OBJECTIVES}")
    muscle = problem.models.muscle
    par = muscle.params
    m, n, dt = muscle.m, problem.n, problem.dt_s
    so_force, so_out = warm_start if warm_start is not None else solve_so(problem, settings)

    sym = ca.SX.sym
    s, a, u = sym("s", m, n), sym("a", m, n), sym("u", m, n)
    d_t = ca.DM(finite_difference_matrix(n, dt, problem.scheme).T)  # x·Dᵀ differentiates each row
    l_m, v_m = ca.DM(problem.l_m.T), ca.DM(problem.v_m.T)
    cos_pen = ca.repmat(ca.DM(np.cos(par.pennation_rad)), 1, n)
    tau_act = ca.repmat(ca.DM(par.activation_time_s), 1, n)

    force, l_se = muscle.stretch_tendon(s)
    v_se = l_se @ d_t  # (4.10)–(4.12), (4.14) on l_se(F) (4.13)
    l_ce, v_ce = muscle.fibre_kinematics(l_se, v_se, l_m, v_m)  # (4.15), (4.17)
    contraction = s ** 2 / cos_pen - a * muscle.flv(l_ce, v_ce)  # (4.16), (4.18) / F_max
    adot = a @ d_t
    activation = (adot - muscle.activation_rate(u, a)) * tau_act  # (4.19)
    moments = moment_constraints(problem, force) / MOMENT_SCALE_NM  # (4.22)
    weights = ca.DM(quadrature_weights(n, problem.periodic))
    if objective == "metabolic":
        rate = muscle.smoothed_metabolic_rate(smoothing)(u, a, l_ce, v_ce, force / cos_pen)  # (A.12)
        cost = dt * (ca.sum1(rate) @ weights)  # (4.29)
    else:
        f_max = ca.repmat(ca.DM(par.max_isometric_force_N), 1, n)
        cost = dt * (ca.sum1((force / f_max) ** 3) @ weights)  # (4.3) integrated over time
    x = ca.vertcat(ca.vec(s), ca.vec(a), ca.vec(u))
    g = ca.vertcat(ca.vec(moments.T), ca.vec(contraction), ca.vec(activation))
    solver = build_solver("eid", x, cost, g, settings=settings)

    s_max = np.sqrt(par.eccentric_asymptote)  # (4.28)
    lbx = np.zeros(3 * m * n)
    ubx = np.concatenate([np.full(m * n, s_max), np.ones(2 * m * n)])  # (4.26), (4.27)
    # warm start: SO forces and the activations/excitations they need, moved inside the bounds
    inv = muscle.invert_forces(so_force, problem.l_m, problem.v_m, dt, problem.scheme)
    s0 = np.clip(np.sqrt(so_force / par.max_isometric_force_N), 0, s_max)
    a0 = np.clip(np.nan_to_num(inv["a"], nan=0.0, posinf=1.0, neginf=0.0), 0, 1)
    u0 = np.clip(np.nan_to_num(inv["u"], nan=0.0, posinf=1.0, neginf=0.0), 0, 1)
    x0 = np.concatenate([s0.ravel(), a0.ravel(), u0.ravel()])  # (n, m) row-major = vec of (m, n)
    out = solve(solver, x0, lbx, ubx, 0.0, 0.0)
    blocks = out.x.reshape(3, n, m)
    s_opt = np.clip(blocks[0], 0.0, s_max)  # IPOPT's bound relaxation is 1e-8 of the bound
    return EidSolution(force_N=par.max_isometric_force_N * s_opt ** 2, activation=blocks[1],
                       excitation=blocks[2], outcome=out, warm_start_outcome=so_out,
                       node_weights=quadrature_weights(n, problem.periodic))
