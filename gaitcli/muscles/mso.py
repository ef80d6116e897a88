"""Modified static optimization (Diss. 4.4, (4.30)–(4.35)).

Frame by frame, the Crowninshield–Brand problem of SO plus 0 ≤ u_j ≤ 1, where
u_j follows from the current forces and the previous frame's force and
activation by backward differences: Ḟ_j (4.31) → a_j (4.32) → ȧ_j (4.33) → u_j
(4.34). The first frame takes the SO forces and an activation from the
contraction inversion with a forward difference to the second SO frame (4.4).

One small NLP is built once and solved for every frame with the frame's data
as parameters. Its variables per muscle are the normalised tendon stretch ŝ
(F = F_max·ŝ², see ``MuscleModel.stretch_tendon``), the activation a and the
excitation u, tied by the contraction (4.18) and activation (2.17) equations,
so that the implicit bounds (4.35) become simple bounds on u; the forces are
bounded by 0 ≤ F ≤ f_asympt·F_max (4.28). The difference
(4.31) is applied to the tendon length l_se(F) (4.13), which gives v_se without
dividing by the tendon stiffness (zero at F = 0).

Infeasible frames (no forces satisfy the moment equations and 0 ≤ u ≤ 1) are
not clipped: the bounds on u carry slacks with a large L1 penalty, the
least-violating solution is kept, and the frames and their violation are reported.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.core.ipopt import Outcome, solve
from gaitcli.core.numerics import MOMENT_SCALE_NM, force_from_stretch, stretch_from_force

from .problem import Problem
from .so import solve_so
from .solver import SolverSettings, build_solver


@dataclass(frozen=True)
class MsoSolution:
    """Forces, activations, excitations (n, m), per-frame IPOPT outcomes, bound violation per frame.

    Frame 0 holds the SO estimate (4.4): ``first_frame`` its fibre length and
    velocity (from the forward difference to the second SO frame); its
    excitation follows from a forward difference of the activations.
    """

    force_N: np.ndarray
    activation: np.ndarray
    excitation: np.ndarray
    first_frame: dict
    so_force_N: np.ndarray
    so_outcome: Outcome
    outcomes: tuple
    violation: np.ndarray  # (n,) largest distance of any u_j outside [0, 1] (0 where feasible)
    time_s: float


def _frame_solver(problem: Problem, penalty: float, settings: SolverSettings | None):
    """NLP of one frame; parameters p = [ŝ_prev, a_prev, l_m, v_m, R (3·m), b (3), Δt]."""
    muscle = problem.models.muscle
    m = muscle.m
    cos_pen = ca.DM(np.cos(muscle.params.pennation_rad))
    tau_act = ca.DM(muscle.params.activation_time_s)
    sym = ca.SX.sym
    s, a, u, lo, hi = sym("s", m), sym("a", m), sym("u", m), sym("lo", m), sym("hi", m)
    s_prev, a_prev, l_m, v_m = sym("s_prev", m), sym("a_prev", m), sym("l_m", m), sym("v_m", m)
    arms, b, dt = sym("R", 3, m), sym("b", 3), sym("dt")
    force, l_se = muscle.stretch_tendon(s)
    _, l_se_prev = muscle.stretch_tendon(s_prev)
    v_se = (l_se - l_se_prev) / dt  # (4.31) on l_se(F) (4.13)
    l_ce, v_ce = muscle.fibre_kinematics(l_se, v_se, l_m, v_m)  # (4.15), (4.17)
    contraction = s ** 2 / cos_pen - a * muscle.flv(l_ce, v_ce)  # (4.16), (4.18) / F_max
    adot = (a - a_prev) / dt  # (4.33)
    activation = (adot - muscle.activation_rate(u, a)) * tau_act  # (4.34)
    moments = (arms @ force - b) / MOMENT_SCALE_NM  # (4.20)
    x = ca.vertcat(s, a, u, lo, hi)
    p = ca.vertcat(s_prev, a_prev, l_m, v_m, ca.vec(arms), b, dt)
    g = ca.vertcat(moments, contraction, activation, u + lo, u - hi)  # last two: (4.35) with slacks
    f = ca.sum1((force / ca.DM(muscle.params.max_isometric_force_N)) ** 3) + penalty * ca.sum1(lo + hi)
    solver = build_solver("mso_frame", x, f, g, p, settings)
    inf = np.inf
    s_max = np.sqrt(muscle.params.eccentric_asymptote)  # F ≤ f_asympt·F_max (4.28)
    lbx = np.concatenate([np.zeros(m), np.zeros(m), np.full(m, -inf), np.zeros(2 * m)])
    ubx = np.concatenate([np.full(m, s_max), np.full(m, inf), np.full(m, inf), np.full(2 * m, inf)])
    lbg = np.concatenate([np.zeros(3 + 2 * m), np.zeros(m), np.full(m, -inf)])
    ubg = np.concatenate([np.zeros(3 + 2 * m), np.full(m, inf), np.ones(m)])
    return solver, lbx, ubx, lbg, ubg


def solve_mso(problem: Problem, settings: SolverSettings | None = None, *,
              penalty: float = 1e4, so: tuple[np.ndarray, Outcome] | None = None) -> MsoSolution:
    """Run MSO over the nodes of ``problem`` in time order (4.30–4.35)."""
    muscle = problem.models.muscle
    m, n, dt = muscle.m, problem.n, problem.dt_s
    f_max = muscle.params.max_isometric_force_N
    so_force, so_out = so if so is not None else solve_so(problem, settings)
    solver, lbx, ubx, lbg, ubg = _frame_solver(problem, penalty, settings)
    # first frame (4.4): SO forces, activation from the contraction inversion with a forward difference
    first = muscle.invert_forces(so_force[:2], problem.l_m[:2], problem.v_m[:2], dt, "central")
    s_prev = stretch_from_force(so_force[0], f_max)
    a_prev = first["a"][0]
    forces, act, exc = np.zeros((n, m)), np.zeros((n, m)), np.zeros((n, m))
    forces[0], act[0] = so_force[0], a_prev
    violation = np.zeros(n)
    outcomes = []
    x_prev = np.concatenate([s_prev, a_prev, a_prev, np.zeros(2 * m)])
    for j in range(1, n):
        p = np.concatenate([s_prev, a_prev, problem.l_m[j], problem.v_m[j],
                            problem.arms[j].T.ravel(), problem.required[j], [dt]])
        out = solve(solver, x_prev, lbx, ubx, lbg, ubg, p)
        outcomes.append(out)
        x = out.x
        s_j = np.maximum(x[:m], 0.0)
        forces[j] = force_from_stretch(s_j, f_max)
        u = x[2 * m:3 * m]
        act[j], exc[j] = x[m:2 * m], u
        violation[j] = max(0.0, float(np.max(-u)), float(np.max(u - 1.0)))
        s_prev, a_prev, x_prev = s_j, x[m:2 * m], x
    exc[0] = muscle.evaluate("excitation", act[0], (act[1] - act[0]) / dt)  # forward difference
    return MsoSolution(force_N=forces, activation=act, excitation=exc,
                       first_frame={"l_ce": first["l_ce"][0], "v_ce": first["v_ce"][0]},
                       so_force_N=so_force, so_outcome=so_out, outcomes=tuple(outcomes),
                       violation=violation, time_s=so_out.time_s + sum(o.time_s for o in outcomes))
