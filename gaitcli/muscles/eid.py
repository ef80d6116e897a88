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

When the NLP is infeasible, :func:`moment_shortfall` solves it once more with
the moment equations relaxed by L1-penalised slacks; the slacks say which joint
moment the muscles cannot produce, by how much and when.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.core.ipopt import Outcome, solve
from gaitcli.core.numerics import MOMENT_SCALE_NM, finite_difference_matrix, force_from_stretch, stretch_from_force
from gaitcli.core.validate import one_of

from .hessian import convex_hessian
from .problem import Problem
from .so import moment_constraints, solve_so
from .solver import SolverSettings, build_solver

OBJECTIVES = ("metabolic", "crowninshield_brand")
#: the limb's moment equations, in the order of the problem's coordinates (4.21)
JOINT_NAMES = ("hip", "knee", "ankle")


@dataclass(frozen=True)
class EidSolution:
    """Forces, activations and excitations (n, m) at all nodes (extra nodes included); the SO forces
    the NLP was warm-started from."""

    force_N: np.ndarray
    activation: np.ndarray
    excitation: np.ndarray
    outcome: Outcome
    warm_start_outcome: Outcome
    warm_start_force_N: np.ndarray
    node_weights: np.ndarray  # (n,) quadrature weights of the objective, in units of Δt


def quadrature_weights(n: int, periodic: bool) -> np.ndarray:
    """Weights w_j of ∫ y dt ≈ Δt·Σ w_j y_j: rectangle rule on a periodic grid, trapezoid otherwise."""
    w = np.ones(n)
    if not periodic:
        w[0] = w[-1] = 0.5
    return w


def _eid_nlp(problem: Problem, objective: str, smoothing: float, shortfall_penalty: float | None):
    """Variables, cost and constraints of the EID NLP (see the module docstring).

    With ``shortfall_penalty`` the moment equations get slack variables (per node and
    coordinate, both signs, in units of MOMENT_SCALE_NM) added to the cost with that
    weight: the problem is then always feasible and the slacks say where and by how much
    the muscles cannot produce the required moments.
    """
    muscle = problem.models.muscle
    par = muscle.params
    m, n, dt = muscle.m, problem.n, problem.dt_s
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
    x = [ca.vec(s), ca.vec(a), ca.vec(u)]
    if shortfall_penalty is not None:
        over, under = sym("over", 3, n), sym("under", 3, n)
        moments = moments - over + under
        cost = cost + shortfall_penalty * (ca.sum1(ca.sum2(over)) + ca.sum1(ca.sum2(under)))
        x += [ca.vec(over), ca.vec(under)]
    g = ca.vertcat(ca.vec(moments.T), ca.vec(contraction), ca.vec(activation))
    return ca.vertcat(*x), cost, g


def _bounds_and_start(problem: Problem, so_force: np.ndarray, extra: int):
    muscle = problem.models.muscle
    par = muscle.params
    m, n = muscle.m, problem.n
    s_max = np.sqrt(par.eccentric_asymptote)  # (4.28)
    lbx = np.zeros(3 * m * n + extra)
    ubx = np.concatenate([np.full(m * n, s_max), np.ones(2 * m * n), np.full(extra, np.inf)])  # (4.26), (4.27)
    # warm start: SO forces and the activations/excitations they need (the solver clips them into the
    # bounds and reports what lay outside: SO's activations may leave [0, 1], Fig. 4.7)
    inv = muscle.invert_forces(so_force, problem.l_m, problem.v_m, problem.dt_s, problem.scheme)
    s0 = stretch_from_force(so_force, par.max_isometric_force_N)
    a0 = np.nan_to_num(inv["a"], nan=0.0, posinf=1.0, neginf=0.0)
    u0 = np.nan_to_num(inv["u"], nan=0.0, posinf=1.0, neginf=0.0)
    x0 = np.concatenate([s0.ravel(), a0.ravel(), u0.ravel(), np.zeros(extra)])  # (n, m) row-major = vec of (m, n)
    return x0, lbx, ubx, s_max


def _blocks(m: int, n: int, extra: int) -> dict[str, slice]:
    """The named blocks of the EID variables (module docstring): ŝ, a, u and the slacks."""
    size = m * n
    return {"stretch": slice(0, size), "activation": slice(size, 2 * size), "excitation": slice(2 * size, 3 * size),
            "slack": slice(3 * size, 3 * size + extra)}


def solve_eid(problem: Problem, settings: SolverSettings | None = None, *, objective: str = "metabolic",
              warm_start: tuple[np.ndarray, Outcome] | None = None, smoothing: float = 1e-2) -> EidSolution:
    """Solve the EID NLP on the nodes of ``problem``, warm-started from SO (Table 4.2).

    ``warm_start`` = (SO forces (n, m), SO outcome) on the same nodes; computed when omitted.
    """
    one_of(objective, OBJECTIVES, where="objective")
    par = problem.models.muscle.params
    m, n = problem.models.muscle.m, problem.n
    so_force, so_out = warm_start if warm_start is not None else solve_so(problem, settings)
    x, cost, g = _eid_nlp(problem, objective, smoothing, None)
    x0, lbx, ubx, s_max = _bounds_and_start(problem, so_force, 0)
    hess = None
    if (settings or SolverSettings()).hessian == "convex" and objective == "metabolic":
        # IPOPT steps on a positive semi-definite curvature of the objective until its steps become small, then
        # on the exact one: the same NLP and KKT points (hessian.py; benchmarks/README.md, "EID's growth with its
        # nodes"); ``curvature``, the callback, stays alive in this frame while IPOPT calls it
        hess, curvature = convex_hessian(problem, smoothing, quadrature_weights(n, problem.periodic), x, cost, g)
    # a trial's moments the muscles cannot make (a locked joint's, carried by an orthosis) make it infeasible
    solver = build_solver("eid", x, cost, g, settings=settings, may_be_infeasible=True, hess_lag=hess)
    out = solve(solver, x0, lbx, ubx, 0.0, 0.0, blocks=_blocks(m, n, 0))
    blocks = out.x.reshape(3, n, m)
    s_opt = np.clip(blocks[0], 0.0, s_max)  # IPOPT's bound relaxation is 1e-8 of the bound
    return EidSolution(force_N=force_from_stretch(s_opt, par.max_isometric_force_N), activation=blocks[1],
                       excitation=blocks[2], outcome=out, warm_start_outcome=so_out, warm_start_force_N=so_force,
                       node_weights=quadrature_weights(n, problem.periodic))


@dataclass(frozen=True)
class MomentShortfall:
    """Where the muscles cannot produce the required moments within 0 ≤ u, a ≤ 1 (an infeasible EID).

    ``shortfall_Nm`` (n, 3): required minus achievable moment (hip flexion, knee flexion,
    ankle dorsiflexion) at each node of the problem; 0 where the muscles suffice.
    """

    shortfall_Nm: np.ndarray
    outcome: Outcome

    def describe(self, time_s: np.ndarray, threshold_Nm: float = 0.01) -> str:
        """One line: each joint's largest shortfall and the time span where it exceeds ``threshold_Nm``."""
        parts = []
        for k, joint in enumerate(JOINT_NAMES):
            short = np.abs(self.shortfall_Nm[:, k])
            where = np.flatnonzero(short > threshold_Nm)
            if where.size:
                parts.append(f"the {joint} moment by up to {short.max():.2f} N·m at t = {time_s[where[0]]:.3f}–"
                             f"{time_s[where[-1]]:.3f} s")
        if not parts:
            return (f"with the moment equations relaxed every one is met within {threshold_Nm} N·m: the failure is "
                    f"numerical, not a lack of muscle strength")
        return "the muscles fall short of " + "; ".join(parts)


def moment_shortfall(problem: Problem, settings: SolverSettings | None = None, *, penalty: float = 1e3,
                     warm_start_force_N: np.ndarray | None = None) -> MomentShortfall:
    """Diagnose an infeasible EID: the same NLP with the moment equations relaxed by L1-penalised
    slacks (Crowninshield–Brand cost), so that the slacks locate what the muscles cannot do.

    ``warm_start_force_N``: SO forces (n, m) on the same nodes (the failed EID's); solved when omitted.
    """
    m, n = problem.models.muscle.m, problem.n
    so_force = warm_start_force_N if warm_start_force_N is not None else solve_so(problem, settings)[0]
    x, cost, g = _eid_nlp(problem, "crowninshield_brand", 0.0, penalty)
    solver = build_solver("eid_shortfall", x, cost, g, settings=settings)
    x0, lbx, ubx, _ = _bounds_and_start(problem, so_force, 6 * n)
    out = solve(solver, x0, lbx, ubx, 0.0, 0.0, blocks=_blocks(m, n, 6 * n))
    over, under = out.x[3 * m * n:3 * m * n + 3 * n], out.x[3 * m * n + 3 * n:]
    # the slacks enter as moments − over + under = 0 with moments = (R·F − b)/scale: R·F − b = over − under
    shortfall = (under - over).reshape(n, 3) * MOMENT_SCALE_NM
    return MomentShortfall(shortfall_Nm=shortfall, outcome=out)
