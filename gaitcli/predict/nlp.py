"""The predictive-gait NLP (Diss. 5.2.7–5.2.9): cost, constraint groups, bounds, scaling, initial guess, IPOPT.

Variables w = [C_y, C_s, T, L, Q, Λ] (all O(1)):

    C_y (5N × 9), C_s (4N × 16)  the segment coefficients p_{k,0…d} of the quartic coordinate splines and
        the cubic tendon-stretch splines, column-major, rows as ``PeriodicSpline.matrix``; the nodal values
        of χ (5.24) are p_{k,0} (5.13), :meth:`NLP.design`
    T (8)  the phase durations per 0.1 s;  L (2)  the step lengths L_r, L_l, m
    Q   I × 100, per distinct instant i, column-major (each column's I values contiguous):
        y (9), ẏ (9), ÿ (9), ŝ (16), rhs (9), l_m (16), v_m (16), a (16), each divided by its
        :data:`LIFTED` scale
    Λ   the ground reactions λ_j of every control point in grid order (the phase's reaction names), per 100 N

C, Q and Λ are the transcription's intermediate quantities made variables ("lifted") and tied
together by equality constraints: the problem is the same as (5.24)'s over χ, but each constraint
touches only a few variables. Evaluated through χ alone every instant depends on every node of
a periodic spline; here instant i reads only the coefficients of the segments ``segments[i]`` ± 1
(:func:`gaitcli.predict.splines.evaluate_window`), chosen where the starting point puts it; a
solution whose instants left their windows is re-solved with new windows
(:meth:`NLP.segments_hold`). At a solution the lifted values equal the transcription of χ
(``problem.py``; λ = G⁺ rhs).

Constraint groups g (CHAPTER5_NOTES §1.9 with the corrections of §3; the first six define C, Q and Λ):

    continuity  the segment coefficients make periodic C3 / C2 splines    (5.14–5.23)
    splines     Q's y, ẏ, ÿ, ŝ = the splines at the instants              (5.10–5.12)
    dynamics    rhs = M ÿ + k − g − Q_p − R f_m                           (5.1)
    paths       l_m, v_m = the muscle paths at (y, ẏ)                     (A.9)
    activation  a = the activation that produces F at (l_ce, v_ce)        (4.18)
    reactions   G_phᵀ (rhs − G_ph λ) = 0: λ = G_ph⁺ rhs                   (5.30)
    moment      |B⁺e| ≤ εm, e = rhs − G_ph λ, per joint and control point (5.49–5.51, 5.53)
    contact     |c_ph| ≤ εk per row and control point                    (5.57)
    unilateral  f_z ≥ 0 at the points in contact                          (5.37–5.40)
    mtp         −10 ≤ m_B ≤ 0 N·m where a foot stands on B alone          (§3 item 3)
    friction    |f_x| ≤ μ f_z per foot down (two linear inequalities)     (5.41–5.42, §3 item 8)
    clearance   z ≥ h_min of the points not in contact                    (5.33–5.36)
    excitation  0 ≤ u ≤ 1 as −t2·a ≤ ȧ ≤ (1 − a)(t1 + t2) with 0 ≤ a ≤ 1 (5.32, §3 item 19)
    speed       ΣT_ph − ΔS/v = 0                                          (5.43)
    shape       LSE(knee in swing) ≥ 60°, LSE(thigh in late stance) ≥ 5°  (5.45–5.48, §3 item 10)

Status (nn = 18, full model, from :func:`initial_guess`): with χ's splines evaluated directly (only
Q's physics lifted) IPOPT with the exact Hessian reached its optimum, J 8.042, after 336 iterations
in 419 s plus 98 s to build the Hessian. With the windowed coefficients the Hessian builds in 25–28 s
and is evaluated in 55–65 ms, the constraint Jacobian in 5 ms; 0.4–0.6 s of each iteration go into
MUMPS (METIS ordering 0.44 s, default 0.6 s, AMD 2.2 s; fixing the durations does not change it).

Bounds: the nodal values p_{k,0}, durations and steps as :func:`box_bounds`; ŝ ≥ 0 (a taut or just
slack tendon, §3 item 18) and 0 ≤ a ≤ 1.
Cost J = w1·Et/100 + w2·Jdev (5.29) with the heat rate's kinks smoothed for the optimiser as in
EID (reported costs use the exact model).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.predict.constraints import GAIT_SHAPE, clearance_phases, feet_in_contact, friction, smooth_max
from gaitcli.predict.cost import DEFAULT_WEIGHTS, cost_of_transport, deviation, objective
from gaitcli.predict.grid import instant_times, periodic_derivative
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import CYCLE_PCT, VARIABLES, Reference
from gaitcli.predict.splines import continuity_matrix, evaluate_window, segment_of

GRAVITY_M_S2 = 9.81
#: the lifted quantities per instant (name, columns, scale: Q = value/scale)
LIFTED = (("y", 9, 1.0), ("yd", 9, 3.0), ("ydd", 9, 30.0), ("stretch", 16, 1.0), ("rhs", 9, 100.0),
          ("l_m", 16, 1.0), ("v_m", 16, 1.0), ("a", 16, 1.0))
LIFTED_COLUMNS = sum(n for _, n, _ in LIFTED)
REACTION_SCALE_N = 100.0
DURATION_SCALE_S = 0.1


def lifted_columns() -> dict[str, slice]:
    """Where each lifted quantity lies among Q's columns."""
    out, start = {}, 0
    for name, n, _ in LIFTED:
        out[name] = slice(start, start + n)
        start += n
    return out


def lifted_scale() -> np.ndarray:
    """(LIFTED_COLUMNS,) scale of Q's columns."""
    return np.concatenate([np.full(n, scale) for _, n, scale in LIFTED])


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
    """The symbolic problem (module docstring): w, J(w), g(w) with bounds, per-group slices of g, box bounds on w.

    ``segments`` (I,): the spline segment each instant was placed near (its window is one segment either
    side); ``parts`` holds Et and Jdev as expressions of w.
    """

    w: ca.SX
    cost: ca.SX
    constraints: ca.SX
    lbg: np.ndarray
    ubg: np.ndarray
    groups: dict[str, slice]
    lbw: np.ndarray
    ubw: np.ndarray
    transcriber: Transcriber
    segments: np.ndarray
    reach: int
    parts: dict = field(default_factory=dict)

    @property
    def spline_size(self) -> int:
        """Length of w's first part: the segment coefficients, durations and step lengths."""
        n = self.transcriber.layout.nodes - 1
        return (5 * 9 + 4 * 16) * n + 10

    def start(self, x: np.ndarray) -> np.ndarray:
        """w for the design vector χ ``x`` (clipped into its box): the coefficients of its splines, Q and Λ
        from the transcription of χ (``problem.py``)."""
        tr = self.transcriber
        low, high = box_bounds(tr)
        x = np.clip(x, low, high)
        blocks = tr.layout.unpack(x)
        t = tr(x)
        opening = tr.grid.instant_points
        rhs = np.vstack(t.generalized_forces)[opening]
        values = {"y": t.y[opening], "yd": t.yd[opening], "ydd": t.ydd[opening], "stretch": t.stretch[opening],
                  "rhs": rhs, "l_m": t.muscle_lengths_m, "v_m": t.muscle_velocities_m_s,
                  "a": np.clip(t.muscle_state["a"], 0.0, 1.0)}
        q = np.nan_to_num(np.column_stack([values[name] for name, _, _ in LIFTED]) / lifted_scale())
        return np.concatenate([(tr.quartic.matrix @ blocks["coordinates"]).ravel(order="F"),
                               (tr.cubic.matrix @ blocks["tendon_stretch"]).ravel(order="F"),
                               blocks["durations"].ravel() / DURATION_SCALE_S, blocks["steps"].ravel(),
                               q.ravel(order="F"), np.concatenate(t.reactions) / REACTION_SCALE_N])

    def design(self, w) -> np.ndarray:
        """χ of w: the nodal values p_{k,0} (5.13), durations and step lengths."""
        w = np.asarray(w, float).ravel()
        n = self.transcriber.layout.nodes - 1
        cq = w[:45 * n].reshape(5 * n, 9, order="F")
        cs = w[45 * n:109 * n].reshape(4 * n, 16, order="F")
        rest = w[109 * n:109 * n + 10]
        return self.transcriber.layout.pack({"coordinates": cq[0::5], "tendon_stretch": cs[0::4],
                                             "durations": rest[:8] * DURATION_SCALE_S, "steps": rest[8:]})

    def segments_hold(self, x: np.ndarray) -> bool:
        """Whether every instant of χ ``x`` lies in its window of segments (the solution is the splines')."""
        return bool(np.all(np.abs(instant_segments(self.transcriber, x) - self.segments) <= self.reach))


def instant_segments(transcriber: Transcriber, x: np.ndarray) -> np.ndarray:
    """The spline segment of each instant of χ ``x`` (their cycle fractions t_i/T)."""
    durations = transcriber.layout.unpack(x)["durations"].ravel()
    return segment_of(transcriber.quartic, instant_times(transcriber.grid, durations) / durations.sum())


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


def _interpolants(table: np.ndarray) -> list[ca.Function]:
    """Linear interpolants over the cycle (%) of a reference table's columns (101 × 10)."""
    return [ca.interpolant(f"reference_{k}", "linear", [CYCLE_PCT], table[:, k]) for k in range(len(VARIABLES))]


def build_nlp(transcriber: Transcriber, reference: Reference, settings: PredictSettings | None = None, *,
              segments=None, reach: int = 0) -> NLP:
    """The lifted NLP of one prediction (module docstring for the variables and groups), each instant reading
    the spline segments ``segments`` ± ``reach`` (default: where the default guess puts the instants)."""
    if segments is None:
        segments = instant_segments(transcriber, initial_guess(transcriber, reference, settings))
    s = settings or PredictSettings()
    model, contact, grid, muscles = transcriber.model, transcriber.contact, transcriber.grid, transcriber.muscles
    params = muscles.muscle.params
    n_i, n = grid.instants, transcriber.layout.nodes - 1
    quartic_spline, cubic_spline = transcriber.quartic, transcriber.cubic
    coordinates = ca.SX.sym("Cq", 5 * n, 9)
    stretches = ca.SX.sym("Cs", 4 * n, 16)
    durations_z, steps = ca.SX.sym("T", 8), ca.SX.sym("L", 2)
    q = ca.SX.sym("Q", n_i, LIFTED_COLUMNS)
    cols, qs = lifted_columns(), lifted_scale()
    value = {name: q[:, cols[name]] * ca.repmat(ca.DM(qs[cols[name]]).T, n_i, 1) for name in cols}
    phases = [int(p) + 1 for p in grid.phase]
    widths = [len(contact.reaction_names[ph]) for ph in phases]
    lam_all = ca.SX.sym("L", sum(widths))
    offsets = np.concatenate([[0], np.cumsum(widths)])
    reactions = [lam_all[offsets[j]:offsets[j + 1]] * REACTION_SCALE_N for j in range(grid.points)]

    durations = durations_z * DURATION_SCALE_S
    steps_r, steps_l = steps[0], steps[1]
    period, stride = ca.sum1(durations), steps_r + steps_l
    times = instant_times(grid, durations)
    groups: dict[str, list] = {name: [] for name in (
        "continuity", "splines", "dynamics", "paths", "activation", "reactions", "moment", "contact", "unilateral",
        "mtp", "friction", "clearance", "excitation", "speed", "shape")}
    bounds: dict[str, list] = {name: [] for name in groups}

    def add(name, expression, low, high):
        expression = ca.vec(expression)
        k = expression.size1()
        groups[name].append(expression)
        bounds[name].append((np.broadcast_to(low, (k,)).astype(float), np.broadcast_to(high, (k,)).astype(float)))

    # the segment coefficients form periodic splines (5.14–5.21, 5.22–5.23); Q's y, ẏ, ÿ, ŝ are their values
    add("continuity", ca.DM(continuity_matrix(quartic_spline)) @ coordinates, 0.0, 0.0)
    add("continuity", ca.DM(continuity_matrix(cubic_spline)) @ stretches, 0.0, 0.0)
    segments = np.asarray(segments, int)
    fractions = times / period
    for i in range(n_i):
        window = (int(segments[i]) - reach, int(segments[i]) + reach)
        rows = [evaluate_window(quartic_spline, coordinates, period, fractions[i], window, r) for r in range(3)]
        drift = stride / period  # hip x: y1 = periodic + (ΔS/T)·t (notes §3 item 4)
        rows[0][0] += drift * times[i]
        rows[1][0] += drift
        rows.append(evaluate_window(cubic_spline, stretches, period, fractions[i], window, 0))
        add("splines", q[i, :cols["stretch"].stop] - ca.horzcat(*rows) / ca.DM(qs[:cols["stretch"].stop]).T,
            0.0, 0.0)
    f_max = np.tile(np.asarray(params.max_isometric_force_N), 2)
    forces = ca.repmat(ca.DM(f_max).T, n_i, 1) * value["stretch"] ** 2  # F = F_max·ŝ² (2.19)
    for i in range(n_i):
        y, yd, ydd = (value[name][i, :].T for name in ("y", "yd", "ydd"))
        f = forces[i, :].T
        rhs = (model.mass_matrix(y) @ ydd + model.bias(y, yd) - model.gravity(y) - muscles.passive(y, yd)
               - muscles.moment_arms(y) @ f)
        add("dynamics", (value["rhs"][i, :].T - rhs) / qs[cols["rhs"]], 0.0, 0.0)
        add("paths", value["l_m"][i, :].T - muscles.lengths(y), 0.0, 0.0)
        add("paths", value["v_m"][i, :].T - muscles.velocities(y, yd), 0.0, 0.0)
    # the muscles: tendon from ŝ, its rate by the unequal-step differences, the activation that makes F
    slack = np.tile(np.asarray(params.tendon_slack_length_m), 2)
    l_se = ca.repmat(ca.DM(slack).T, n_i, 1) * (1 + params.tendon_strain_at_max_force * value["stretch"])
    v_se = periodic_derivative(l_se, times, period)
    a = value["a"]
    adot = periodic_derivative(a, times, period)
    rate = []
    for k in (0, 1):
        c = slice(8 * k, 8 * k + 8)
        args = (forces[:, c].T, v_se[:, c].T, value["l_m"][:, c].T, value["v_m"][:, c].T)
        add("activation", a[:, c] - muscles.muscle.activation_from_force(*args).T, 0.0, 0.0)
        l_ce, v_ce = muscles.muscle.fibre_kinematics(l_se[:, c].T, v_se[:, c].T, args[2], args[3])
        u = muscles.muscle.excitation(a[:, c].T, adot[:, c].T)
        f_ce = forces[:, c].T / ca.repmat(ca.DM(np.cos(params.pennation_rad)), 1, n_i)
        rate.append(transcriber.metabolic(u, a[:, c].T, l_ce, v_ce, f_ce).T)
    t1 = np.tile(np.asarray(params.activation_t1_per_s), 2)
    t2 = np.tile(np.asarray(params.activation_t2_per_s), 2)
    T1, T2 = ca.repmat(ca.DM(t1).T, n_i, 1), ca.repmat(ca.DM(t2).T, n_i, 1)

    # per control point: reactions, moment error, contact, ground forces, clearance
    foot_forces = []  # per control point: (f_x, f_z) of each foot, N
    joint_map_pinv = ca.DM(transcriber.joint_map_pinv)
    for j, phase in enumerate(phases):
        i = int(grid.instant[j])
        y = value["y"][i, :].T + (ca.DM([1.0] + [0.0] * 8) * stride if grid.wraps[j] else 0)
        G = contact.reaction_matrix[phase](y)
        lam = reactions[j]
        e = value["rhs"][i, :].T - G @ lam
        add("reactions", G.T @ e / REACTION_SCALE_N, 0.0, 0.0)
        add("moment", joint_map_pinv @ e, -s.moment_tolerance_Nm, s.moment_tolerance_Nm)
        add("contact", contact.constraint[phase](y, steps_r, steps_l, 0.0), -s.contact_tolerance_m,
            s.contact_tolerance_m)
        names = contact.reaction_names[phase]
        feet = {}
        for side in ("r", "l"):
            fx = sum((lam[k] for k, name in enumerate(names) if name.endswith(f"_{side}_fx_N")), ca.SX(0))
            fz = sum((lam[k] for k, name in enumerate(names) if name.endswith(f"_{side}_fz_N")), ca.SX(0))
            feet[side] = (fx, fz)
        foot_forces.append(feet)
        for k, name in enumerate(names):
            if name.endswith("_fz_N"):
                add("unilateral", lam[k], 0.0, np.inf)
            elif name.endswith("_moment_Nm"):
                add("mtp", lam[k], *s.mtp_moment_Nm)
        for side in feet_in_contact(phase):
            add("friction", ca.vertcat(*friction(*feet[side], s.friction_coefficient)), -np.inf, 0.0)
        points = dict(zip(model.point_names, model.points(y)))
        for point in ("heel_r", "mtp_r", "heel_l", "mtp_l"):
            if phase in clearance_phases(point):
                add("clearance", points[point][1], s.clearance_m, np.inf)
    add("excitation", adot + T2 * a, 0.0, np.inf)
    add("excitation", (1 - a) * (T1 + T2) - adot, 0.0, np.inf)
    add("speed", period - stride / s.speed_m_s, 0.0, 0.0)
    for name, (index, shape_phases, minimum) in GAIT_SHAPE.items():
        chosen = [int(grid.instant[j]) for j in range(grid.points) if phases[j] in shape_phases]
        add("shape", smooth_max(ca.vertcat(*[value["y"][i, index] for i in sorted(set(chosen))])), minimum, np.inf)

    # cost: Et (5.27) and Jdev (5.28) at the instants
    et = cost_of_transport(ca.horzcat(*rate), times, period, stride)
    mass = model.total_mass_kg
    rows = []
    for i, j in enumerate(grid.instant_points):
        yi = value["y"][i, :]
        angles = [*walker_joint_angles(yi[2], yi[3], yi[4], yi[5]), *walker_joint_angles(yi[2], yi[6], yi[7], yi[8])]
        feet = foot_forces[int(j)]
        forces_i = [feet["r"][0], feet["r"][1], feet["l"][0], feet["l"][1]]
        rows.append(ca.horzcat(*[ang * 180 / np.pi for ang in angles], *[f / mass for f in forces_i]))
    pct = 100 * times / period
    means = ca.horzcat(*[f(pct) for f in _interpolants(reference.mean)])
    sds = ca.horzcat(*[f(pct) for f in _interpolants(reference.sd)])
    jdev = deviation(ca.vertcat(*rows), means, sds, times, period)
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
    blocks_low, blocks_high = transcriber.layout.unpack(low), transcriber.layout.unpack(high)
    spline_low, spline_high = [], []
    for name, spline, columns in (("coordinates", quartic_spline, 9), ("tendon_stretch", cubic_spline, 16)):
        width = spline.degree + 1
        lo, hi = np.full((width * n, columns), -np.inf), np.full((width * n, columns), np.inf)
        lo[0::width], hi[0::width] = blocks_low[name], blocks_high[name]  # the nodal values p_{k,0} (5.13)
        spline_low.append(lo.ravel(order="F"))
        spline_high.append(hi.ravel(order="F"))
    spline_low += [blocks_low["durations"].ravel() / DURATION_SCALE_S, blocks_low["steps"].ravel()]
    spline_high += [blocks_high["durations"].ravel() / DURATION_SCALE_S, blocks_high["steps"].ravel()]
    q_low, q_high = np.full((n_i, LIFTED_COLUMNS), -np.inf), np.full((n_i, LIFTED_COLUMNS), np.inf)
    q_low[:, cols["stretch"]] = 0.0  # ŝ ≥ 0: a taut or just slack tendon (§3 item 18)
    q_low[:, cols["a"]], q_high[:, cols["a"]] = 0.0, 1.0
    n_l = lam_all.size1()
    w = ca.vertcat(ca.vec(coordinates), ca.vec(stretches), durations_z, steps, ca.vec(q), lam_all)
    return NLP(w=w, cost=cost, constraints=ca.vertcat(*exprs), lbg=np.concatenate(lows), ubg=np.concatenate(highs),
               groups=slices, lbw=np.concatenate([*spline_low, q_low.ravel(order="F"), np.full(n_l, -np.inf)]),
               ubw=np.concatenate([*spline_high, q_high.ravel(order="F"), np.full(n_l, np.inf)]),
               transcriber=transcriber, segments=segments, reach=reach, parts={"Et": et, "Jdev": jdev})


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


def solve(nlp: NLP, x0: np.ndarray, settings: PredictSettings | None = None, *, w0: np.ndarray | None = None,
          options: dict | None = None) -> dict:
    """IPOPT with exact derivatives (Hessian included) from χ ``x0`` (or the whole ``w0``); returns χ, w, the
    status, iterations and cost. ``options``: further IPOPT/CasADi options."""
    s = settings or PredictSettings()
    problem = {"x": nlp.w, "f": nlp.cost, "g": nlp.constraints}
    opts = {"print_time": False, "ipopt.print_level": s.print_level, "ipopt.sb": "yes",
            "ipopt.max_iter": s.max_iterations, "ipopt.tol": s.tolerance, "ipopt.mu_strategy": "adaptive",
            "ipopt.mumps_pivot_order": 5}  # METIS: the fastest ordering measured on this KKT system
    opts.update(options or {})
    solver = ca.nlpsol("predict", "ipopt", problem, opts)
    start = nlp.start(x0) if w0 is None else w0
    result = solver(x0=start, lbx=nlp.lbw, ubx=nlp.ubw, lbg=nlp.lbg, ubg=nlp.ubg)
    stats = solver.stats()
    w = np.array(result["x"]).ravel()
    return {"x": nlp.design(w), "w": w, "status": stats.get("return_status", ""),
            "success": bool(stats.get("success")), "iterations": int(stats.get("iter_count", -1)),
            "cost": float(result["f"])}


def solve_windowed(transcriber: Transcriber, reference: Reference, x0: np.ndarray,
                   settings: PredictSettings | None = None, *, rounds: int = 4, options: dict | None = None) -> dict:
    """:func:`solve` with the spline windows placed where ``x0`` puts the instants, re-placed and re-solved
    from the last solution while a solution's instants leave their windows (at most ``rounds`` solves).
    Adds ``rounds`` (solves made) and ``windows_hold`` to the result."""
    x, w, total = x0, None, 0
    for k in range(1, rounds + 1):
        nlp = build_nlp(transcriber, reference, settings, segments=instant_segments(transcriber, x))
        result = solve(nlp, x, settings, w0=w, options=options)
        total += result["iterations"]
        x, w = result["x"], result["w"]
        if nlp.segments_hold(x):
            break
    return {**result, "iterations": total, "rounds": k, "windows_hold": nlp.segments_hold(x)}
