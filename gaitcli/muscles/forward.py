"""Validation by forward integration (Diss. 4.5.4): EID excitations → motion (2.28, 2.29).

The state x = (a, s, q, q̇) holds the activations, the tendon stretches
s = l_se − l_slack (the force state of (2.28) in a form that is also defined
for a slack tendon), the limb coordinates and their rates. The excitations are
the EID nodal values interpolated linearly in time; the hip trajectory and
the ground reaction are prescribed as in the inverse problem. The initial
state is the EID state at the first node of the interval. The result is
compared with the input kinematics (RMS, deg) and its metabolic cost with the
EID estimate.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from .hill import NQ
from .limb import MotionInterpolant
from .problem import Problem


@dataclass(frozen=True)
class ValidationResult:
    """Forward simulation driven by the EID excitations, against the input motion.

    ``angles_rad``/``reference_rad`` (n, 3) at ``time_s``; ``rms_deg`` (3,) per
    coordinate (thigh, knee, ankle) and ``rms_total_deg`` over all three;
    ``metabolic_cost_forward_J`` of the simulation and ``metabolic_cost_eid_J`` of the
    EID over the same interval; ``success``/``message`` from the integrator;
    ``restarted_at_nodes``: each inter-node interval integrated from the EID state
    at its first node rather than one integration from the first node.
    """

    time_s: np.ndarray
    angles_rad: np.ndarray
    reference_rad: np.ndarray
    force_N: np.ndarray
    activation: np.ndarray
    rms_deg: np.ndarray
    rms_total_deg: float
    metabolic_cost_forward_J: float
    metabolic_cost_eid_J: float
    success: bool
    message: str
    restarted_at_nodes: bool = False


def state_equations(problem: Problem) -> tuple[ca.Function, ca.Function]:
    """ẋ = f(x, u, hip, ḧ, f_gr, c_x) (2.29) and its Jacobian ∂f/∂x, as CasADi Functions."""
    models = problem.models
    muscle, limb, joints = models.muscle, models.limb, models.joints
    m = muscle.m
    sym = ca.SX.sym
    x, u = sym("x", 2 * m + 2 * NQ), sym("u", m)
    hip, hip_acc, grf, cop = sym("hip", 2), sym("hip_acc", 2), sym("grf", 2), sym("cop_x")
    a, s, q, qd = x[:m], x[m:2 * m], x[2 * m:2 * m + NQ], x[2 * m + NQ:]
    adot = muscle.activation_rate(u, a)  # (2.17)
    angles, rates = limb.joint_angles(q), limb.joint_angles(qd)  # ψ = q for the limb: joint moments are τ
    sdot, force, _, _ = muscle.contraction_rate(a, s, muscle.length(angles), muscle.velocity(angles, rates))  # (2.25)
    tau = muscle.moment_arms(angles) @ force + joints.total(angles, rates)
    qdd = limb.forward_dynamics(q, qd, tau, hip, hip_acc, grf, cop)  # (2.13)
    xdot = ca.vertcat(adot, sdot, qd, qdd)
    args = [x, u, hip, hip_acc, grf, cop]
    names = ["x", "u", "hip", "hip_acc", "grf", "cop_x"]
    return (ca.Function("xdot", args, [xdot], names, ["xdot"]),
            ca.Function("xdot_jac", args, [ca.jacobian(xdot, x)], names, ["jac"]))


def validate_forward(problem: Problem, motion_interp: MotionInterpolant, force_N: np.ndarray,
                     activation: np.ndarray, excitation: np.ndarray, metabolic_cost_eid_J: float, *,
                     restart_at_nodes: bool = False, samples_per_node: int = 5, rtol: float = 1e-6,
                     atol: float = 1e-9) -> ValidationResult:
    """Integrate (2.29) over the interval of interest with the EID excitations.

    Excitations between nodes are linear in time (periodically wrapped for a full cycle).

    Parameters
    ----------
    problem : Problem
        The EID problem.
    motion_interp : MotionInterpolant
        The prescribed hip path and ground reaction between nodes.
    force_N, activation, excitation : numpy.ndarray
        EID values (n, m) at all nodes of ``problem`` (extra nodes included).
    metabolic_cost_eid_J : float
        The EID's cost over the interval, for the comparison.
    restart_at_nodes : bool
        False: one integration from the EID state at the first node (4.5.4). True: every
        inter-node interval starts again from the EID state at its first node (the variant the
        dissertation expects to agree even better); open-loop integration over a whole stance
        with prescribed ground reactions drifts, this one measures the discretisation only.
    samples_per_node : int
        Output samples per inter-node interval.
    rtol, atol : float
        The integrator's tolerances.
    """
    muscle = problem.models.muscle
    par = muscle.params
    m = muscle.m
    rhs, jac = state_equations(problem)
    t_nodes = problem.time_s
    u_nodes = excitation
    if problem.periodic:
        t_nodes = np.append(t_nodes, t_nodes[-1] + problem.dt_s)
        u_nodes = np.vstack([excitation, excitation[:1]])
    first, stop = problem.interval.start, problem.interval.stop
    t0, t1 = problem.t_start_s, problem.t_end_s

    def inputs(t):
        smp = motion_interp(np.array([t]))
        u = np.array([np.interp(t, t_nodes, u_nodes[:, i]) for i in range(m)])
        return u, smp.hip_m[0], smp.hip_acc[0], smp.grf_N[0], smp.cop_x_m[0]

    def f(t, x):
        return np.array(rhs(x, *inputs(t))).ravel()

    def f_jac(t, x):
        return np.array(jac(x, *inputs(t)))

    def node_state(j, t):
        smp = motion_interp(np.array([t]))
        stretch = np.sqrt(force_N[j] / par.tendon_stiffness_N_per_m2)
        return np.concatenate([activation[j], stretch, smp.q[0], smp.qd[0]])

    if restart_at_nodes:
        starts = [(j, t_nodes[j]) for j in range(first, stop if problem.periodic else stop - 1)]
        spans = [(t, t_nodes[j + 1] if j + 1 < t_nodes.size else t1) for j, t in starts]
    else:
        starts, spans = [(first, t0)], [(t0, t1)]
    per_segment = samples_per_node if restart_at_nodes else samples_per_node * (stop - first)
    times, states, costs, ok, messages = [], [], [], True, set()
    for (j, ta), (_, tb) in zip(starts, spans):
        t_eval = np.linspace(ta, tb, per_segment + 1)
        from scipy.integrate import solve_ivp  # only --validate integrates: not at import

        sol = solve_ivp(f, (ta, tb), node_state(j, ta), method="Radau", t_eval=t_eval, jac=f_jac,
                        rtol=rtol, atol=atol)
        ok &= bool(sol.success and sol.t.size == t_eval.size)
        messages.add(str(sol.message))
        rate = _metabolic_rate(problem.models, sol.t, sol.y.T, t_nodes, u_nodes)
        costs.append(float(np.trapezoid(rate, sol.t)) if sol.t.size > 1 else float("nan"))
        keep = slice(0 if not times else 1, None)  # segment starts after the first equal the input
        times.append(sol.t[keep])
        states.append(sol.y.T[keep])
    t_out, xs = np.concatenate(times), np.vstack(states)
    ref = motion_interp(t_out)
    angles = xs[:, 2 * m:2 * m + NQ]
    err_deg = np.rad2deg(angles - ref.q)
    force, _, _ = _contraction_along(problem.models, xs)
    return ValidationResult(time_s=t_out, angles_rad=angles, reference_rad=ref.q, force_N=force,
                            activation=xs[:, :m], rms_deg=np.sqrt(np.mean(err_deg ** 2, axis=0)),
                            rms_total_deg=float(np.sqrt(np.mean(err_deg ** 2))),
                            metabolic_cost_forward_J=float(np.sum(costs)),
                            metabolic_cost_eid_J=float(metabolic_cost_eid_J), success=ok,
                            message="; ".join(sorted(messages)), restarted_at_nodes=restart_at_nodes)


def _contraction_along(models, xs) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tendon force, fibre length and fibre velocity (n, m) along simulated states ``xs`` (n, 2m + 6) (2.25)."""
    muscle, limb = models.muscle, models.limb
    m = muscle.m
    angles = limb.evaluate("joint_angles", xs[:, 2 * m:2 * m + NQ])
    rates = limb.evaluate("joint_angles", xs[:, 2 * m + NQ:])
    _, force, l_ce, v_ce = muscle.evaluate("contraction_rate", xs[:, :m], xs[:, m:2 * m],
                                           muscle.evaluate("length", angles),
                                           muscle.evaluate("velocity", angles, rates))
    return force, l_ce, v_ce


def _metabolic_rate(models, t, xs, t_nodes, u_nodes) -> np.ndarray:
    """Total metabolic rate (W) along a simulated trajectory (A.12)."""
    muscle = models.muscle
    m = muscle.m
    force, l_ce, v_ce = _contraction_along(models, xs)
    u = np.column_stack([np.interp(t, t_nodes, u_nodes[:, i]) for i in range(m)])
    f_ce = force / np.cos(muscle.params.pennation_rad)
    return muscle.evaluate("metabolic_rate", u, xs[:, :m], l_ce, v_ce, f_ce).sum(axis=1)
