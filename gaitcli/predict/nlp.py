"""The predictive-gait NLP (Diss. 5.2.7–5.2.9): cost, constraint groups, bounds, scaling, initial guess, IPOPT.

Status: built and evaluated, not yet solved to convergence. From :func:`initial_guess`, 300 IPOPT
iterations (limited-memory Hessian) take 212 s and end with every constraint group within 0.04 of its
bounds (J 13.9, Et 601 J/m, Jdev 8.8); 1500 iterations (1205 s) end feasible in every group, J 9.0,
Et 375 J/m, Jdev 6.0, still not declared optimal. The per-point MX graph costs 0.7–0.8 s per iteration.

Variables: the design vector χ of the full model (``layout.py``), optimised as
z = χ / scale (coordinates in rad or m, tendon stretch ŝ as it is, durations per
0.1 s, step lengths in m: all O(1)). Constraint groups g (CHAPTER5_NOTES §1.9 with the
corrections of §3):

    moment      |B⁺e| ≤ εm per joint and control point                 (5.49–5.51, 5.53)
    contact     |c_ph| ≤ εk per row and control point                  (5.57)
    unilateral  f_z ≥ 0 at the points in contact                        (5.37–5.40)
    mtp         −10 ≤ m_B ≤ 0 N·m where a foot stands on B alone        (§3 item 3)
    friction    |f_x| ≤ μ f_z per foot down (two linear inequalities)   (5.41–5.42, §3 item 8)
    clearance   z ≥ h_min of the points not in contact                  (5.33–5.36)
    excitation  0 ≤ u ≤ 1 as −t2·a ≤ ȧ ≤ (1 − a)(t1 + t2), 0 ≤ a ≤ 1   (5.32, §3 item 19)
    stretch     ŝ ≥ 0 at the instants (a taut or just slack tendon)     (§3 item 18)
    speed       ΣT_ph − ΔS/v = 0                                        (5.43)
    shape       LSE(knee in swing) ≥ 60°, LSE(thigh in late stance) ≥ 5° (5.45–5.48, §3 item 10)

Cost J = w1·Et/100 + w2·Jdev (5.29) with the heat rate's kinks smoothed for the
optimiser as in EID (reported costs use the exact model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.predict.constraints import GAIT_SHAPE, clearance_phases, feet_in_contact, friction, smooth_max
from gaitcli.predict.cost import DEFAULT_WEIGHTS, cost_of_transport, deviation, objective
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import CYCLE_PCT, VARIABLES, Reference

GRAVITY_M_S2 = 9.81


@dataclass(frozen=True)
class PredictSettings:
    """The settings of one prediction (defaults: the dissertation's 5.2.10 and 5.3.1, and our stated choices)."""

    speed_m_s: float = 1.1275
    weights: tuple[float, float] = DEFAULT_WEIGHTS
    moment_tolerance_Nm: float = 2.0
    contact_tolerance_m: float = 0.002
    friction_coefficient: float = 0.8
    clearance_m: float = 0.0
    mtp_moment_Nm: tuple[float, float] = (-10.0, 0.0)
    smoothing: float = 1e-2
    max_iterations: int = 3000
    tolerance: float = 1e-6
    print_level: int = 0


@dataclass
class NLP:
    """The symbolic problem: z, J(z), g(z) with bounds, per-group slices of g, and box bounds on z."""

    z: ca.MX
    cost: ca.MX
    constraints: ca.MX
    lbg: np.ndarray
    ubg: np.ndarray
    groups: dict[str, slice]
    lbz: np.ndarray
    ubz: np.ndarray
    scale: np.ndarray
    parts: dict = field(default_factory=dict)  # Et, Jdev as expressions


def variable_scale(transcriber: Transcriber) -> np.ndarray:
    """χ = scale · z."""
    layout = transcriber.layout
    scale = np.ones(layout.size)
    start = layout.blocks["durations"][0]
    scale[start:start + 8] = 0.1
    return scale


def box_bounds(transcriber: Transcriber) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on χ (5.44; no numbers printed: ranges of motion and magnitudes wide enough for walking)."""
    layout = transcriber.layout
    low, high = np.full(layout.size, -np.inf), np.full(layout.size, np.inf)
    start, rows, _ = layout.blocks["coordinates"]
    ranges = [(-0.5, 0.5), (0.5, 1.3), (-0.6, 0.6), (-1.2, 1.0), (0.0, 1.7), (-0.8, 0.8),
              (-1.2, 1.0), (0.0, 1.7), (-0.8, 0.8)]  # hip x (periodic part), hip z, HAT, thigh, knee, ankle
    for k, (lo, hi) in enumerate(ranges):
        low[start + k * rows:start + (k + 1) * rows], high[start + k * rows:start + (k + 1) * rows] = lo, hi
    start, rows, cols = layout.blocks["tendon_stretch"]
    low[start:start + rows * cols], high[start:start + rows * cols] = 0.0, 1.3  # F ≤ 1.69 F_max
    start = layout.blocks["durations"][0]
    low[start:start + 8], high[start:start + 8] = 0.01, 0.8
    start = layout.blocks["steps"][0]
    low[start:start + 2], high[start:start + 2] = 0.2, 1.2
    return low, high


def _interpolants(reference: Reference) -> list[ca.Function]:
    return [ca.interpolant(f"ref_{k}", "linear", [CYCLE_PCT], reference.mean[:, k]) for k in range(len(VARIABLES))]


def build_nlp(transcriber: Transcriber, reference: Reference, settings: PredictSettings | None = None) -> NLP:
    """The NLP of one prediction (module docstring for the groups)."""
    s = settings or PredictSettings()
    scale = variable_scale(transcriber)
    z = ca.MX.sym("z", transcriber.layout.size)
    t = transcriber(z * ca.DM(scale))
    model, contact, grid = transcriber.model, transcriber.contact, transcriber.grid
    groups: dict[str, list] = {name: [] for name in ("moment", "contact", "unilateral", "mtp", "friction",
                                                     "clearance", "excitation", "stretch", "speed", "shape")}
    bounds: dict[str, list] = {name: [] for name in groups}

    def add(name, expression, low, high):
        expression = ca.vec(expression)
        n = expression.size1()
        groups[name].append(expression)
        bounds[name].append((np.broadcast_to(low, (n,)).astype(float), np.broadcast_to(high, (n,)).astype(float)))

    foot_forces = []  # per control point: (f_x, f_z) of each foot, N
    for j in range(grid.points):
        phase = int(grid.phase[j]) + 1
        names = contact.reaction_names[phase]
        lam = t.reactions[j]
        add("moment", t.moment_error_Nm[j], -s.moment_tolerance_Nm, s.moment_tolerance_Nm)
        add("contact", t.contact_error_m[j], -s.contact_tolerance_m, s.contact_tolerance_m)
        feet = {}
        for side in ("r", "l"):
            fx = sum((lam[i] for i, n in enumerate(names) if n.endswith(f"_{side}_fx_N")), ca.MX(0))
            fz = sum((lam[i] for i, n in enumerate(names) if n.endswith(f"_{side}_fz_N")), ca.MX(0))
            feet[side] = (fx, fz)
        foot_forces.append(feet)
        for i, n in enumerate(names):
            if n.endswith("_fz_N"):
                add("unilateral", lam[i], 0.0, np.inf)
            elif n.endswith("_moment_Nm"):
                add("mtp", lam[i], *s.mtp_moment_Nm)
        for side in feet_in_contact(phase):
            add("friction", ca.vertcat(*friction(*feet[side], s.friction_coefficient)), -np.inf, 0.0)
        points = dict(zip(model.point_names, model.points(t.y[j, :].T)))
        for point in ("heel_r", "mtp_r", "heel_l", "mtp_l"):
            if phase in clearance_phases(point):
                add("clearance", points[point][1], s.clearance_m, np.inf)
    p = transcriber.muscles.muscle.params
    t1 = np.tile(np.asarray(p.activation_t1_per_s), 2)
    t2 = np.tile(np.asarray(p.activation_t2_per_s), 2)
    a, adot = t.muscle_state["a"], t.muscle_state["adot"]
    instants = a.size1()
    T1, T2 = ca.repmat(ca.DM(t1).T, instants, 1), ca.repmat(ca.DM(t2).T, instants, 1)
    add("excitation", adot + T2 * a, 0.0, np.inf)
    add("excitation", (1 - a) * (T1 + T2) - adot, 0.0, np.inf)
    add("excitation", a, 0.0, 1.0)
    add("stretch", t.stretch[[int(i) for i in grid.instant_points], :], 0.0, np.inf)
    add("speed", t.period_s - t.stride_m / s.speed_m_s, 0.0, 0.0)
    for name, (index, phases, minimum) in GAIT_SHAPE.items():
        chosen = [j for j in range(grid.points) if int(grid.phase[j]) + 1 in phases]
        add("shape", smooth_max(ca.vertcat(*[t.y[j, index] for j in chosen])), minimum, np.inf)

    # cost: Et (5.27) and Jdev (5.28) at the instants
    et = cost_of_transport(t.metabolic_rate_W, t.instant_times_s, t.period_s, t.stride_m)
    opening = [int(i) for i in grid.instant_points]
    mass = model.total_mass_kg
    rows = []
    for j in opening:
        yj = t.y[j, :]
        angles = [*walker_joint_angles(yj[2], yj[3], yj[4], yj[5]), *walker_joint_angles(yj[2], yj[6], yj[7], yj[8])]
        forces = [foot_forces[j]["r"][0], foot_forces[j]["r"][1], foot_forces[j]["l"][0], foot_forces[j]["l"][1]]
        rows.append(ca.horzcat(*[ang * 180 / np.pi for ang in angles], *[f / mass for f in forces]))
    values = ca.vertcat(*rows)
    pct = 100 * t.instant_times_s / t.period_s
    interpolants = _interpolants(reference)
    means = ca.horzcat(*[f(pct) for f in interpolants])
    sds = ca.horzcat(*[ca.interpolant(f"sd_{k}", "linear", [CYCLE_PCT], reference.sd[:, k])(pct)
                       for k in range(len(VARIABLES))])
    jdev = deviation(values, means, sds, t.instant_times_s, t.period_s)
    cost = objective(et, jdev, s.weights)

    exprs, lows, highs, slices, start = [], [], [], {}, 0
    for name in groups:
        if not groups[name]:
            continue
        block = ca.vertcat(*groups[name])
        exprs.append(block)
        lows += [b[0] for b in bounds[name]]
        highs += [b[1] for b in bounds[name]]
        slices[name] = slice(start, start + block.size1())
        start += block.size1()
    low, high = box_bounds(transcriber)
    return NLP(z=z, cost=cost, constraints=ca.vertcat(*exprs), lbg=np.concatenate(lows), ubg=np.concatenate(highs),
               groups=slices, lbz=low / scale, ubz=high / scale, scale=scale, parts={"Et": et, "Jdev": jdev})


def initial_guess(transcriber: Transcriber, reference: Reference,
                  settings: PredictSettings | None = None) -> np.ndarray:
    """χ from the reference's angles (HAT upright), a hip height that puts the standing foot on the floor,
    phase durations of a 60 % stance, equal steps for the speed, forces at 10 % of F_max (ŝ = √0.1)."""
    s = settings or PredictSettings()
    layout, p = transcriber.layout, transcriber.model.params
    n = layout.nodes - 1
    pct = 100 * np.arange(n) / n
    mean = np.column_stack([np.interp(pct, CYCLE_PCT, reference.mean[:, k]) for k in range(len(VARIABLES))])
    rad = np.radians
    hip_flex_r, knee_r, dorsi_r, hip_flex_l, knee_l, dorsi_l = (mean[:, VARIABLES.index(v)] for v in VARIABLES[:6])
    leg = p.limb.thigh_length_m + p.limb.shank_length_m + p.contact_below_ankle_m
    coordinates = np.column_stack([np.zeros(n), np.full(n, 0.97 * leg), np.zeros(n),
                                   -rad(hip_flex_r), rad(knee_r), -rad(dorsi_r),
                                   -rad(hip_flex_l), rad(knee_l), -rad(dorsi_l)])
    step = 0.62  # m: about half of a 1.24 m stride at the dissertation's subject 1's speed
    half = step / s.speed_m_s  # s: half a cycle
    durations = np.array([0.07, 0.13, 0.55, 0.25] * 2) * half
    return layout.pack({"coordinates": coordinates, "tendon_stretch": np.full((n, 16), np.sqrt(0.1)),
                        "durations": durations,
                        "steps": [step, step]})


def solve(nlp: NLP, x0: np.ndarray, settings: PredictSettings | None = None, *, callback=None) -> dict:
    """IPOPT with exact derivatives from ``x0`` (χ); returns χ, status, iterations, the cost parts."""
    s = settings or PredictSettings()
    problem = {"x": nlp.z, "f": nlp.cost, "g": nlp.constraints}
    options = {"print_time": False, "ipopt.print_level": s.print_level, "ipopt.sb": "yes",
               "ipopt.max_iter": s.max_iterations, "ipopt.tol": s.tolerance, "ipopt.mu_strategy": "adaptive",
               "ipopt.hessian_approximation": "limited-memory"}
    solver = ca.nlpsol("predict", "ipopt", problem, options)
    z0 = np.clip(x0 / nlp.scale, nlp.lbz, nlp.ubz)
    result = solver(x0=z0, lbx=nlp.lbz, ubx=nlp.ubz, lbg=nlp.lbg, ubg=nlp.ubg)
    stats = solver.stats()
    z = np.array(result["x"]).ravel()
    return {"x": z * nlp.scale, "status": stats.get("return_status", ""), "success": bool(stats.get("success")),
            "iterations": int(stats.get("iter_count", -1)), "cost": float(result["f"])}
