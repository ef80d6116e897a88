"""The predictive-gait NLP (Diss. 5.2.7–5.2.9): cost, constraint groups, bounds, scaling, initial guess, IPOPT.

Variables w = [C…, T, L, Q…, Λ] (all O(1)); full model:

    C_y (5N × 9), C_s (4N × 16)  the segment coefficients p_{k,0…d} of the quartic coordinate splines and
        the cubic tendon-stretch splines, column-major, rows as ``PeriodicSpline.matrix``; the nodal values
        of χ (5.24) are p_{k,0} (5.13), :meth:`NLP.design`
    T (8)  the phase durations per 0.1 s;  L (2)  the step lengths L_r, L_l, m
    Q   I × 100, per distinct instant i, column-major (each column's I values contiguous):
        y (9), ẏ (9), ÿ (9), ŝ (16), rhs (9), l_m (16), v_m (16), a (16), each divided by its
        :data:`LIFTED_SCALE`
    Λ   the ground reactions λ_j of every control point in grid order (the phase's reaction names), per 100 N
    D   (prosthetic models only) the device's (a_p, b_p, c0, a_n, b_n, d_prosth) of (5.58)–(5.59), each
        divided by its :data:`DEVICE_SCALE`: fixed by equal bounds for a given foot, free within
        :data:`DEVICE_BOUNDS` for the optimal prosthesis (5.3.3)

Parameters p = (v, w1, w2): the speed (5.43) and the weights (5.29), so that one built problem (and its
compiled solver, :func:`solver_for`) serves every speed and weight set of a study. Muscles removed with a
prosthetic ankle (``WalkerMuscles.present``) keep their places in w, fixed at zero by their bounds, and
have no constraint rows and no cost.

Symmetric model (``layout.py``; left = right half a cycle later): C_t (5N_h × 3) the trunk's T/2-periodic
quartics, C_y (5N × 3) and C_s (4N × 8) the right leg's; T (4), L (1); Q (I × 41): the right leg's y, ẏ, ÿ
(3 each), ŝ, l_m, v_m, a (8 each); P (I/2 × 18): the trunk's y, ẏ, ÿ (3 each) and rhs (9) over the first half
cycle; Λ at the first half's 44 points. Only the first half cycle's physics and the right leg's muscles are
stated; the rest is their mirror image.

C, Q (P) and Λ are the transcription's intermediate quantities made variables ("lifted") and tied
together by equality constraints: the problem is the same as (5.24)'s over χ, but each constraint
touches only a few variables. Evaluated through χ alone every instant depends on every node of
a periodic spline; here instant i reads only the coefficients of the segments ``segments[i]`` ± reach
(:func:`gaitcli.predict.splines.window_values`; ``PredictSettings.window_reach``), placed where the
starting point puts it, and a ``windows`` constraint keeps it there (never extrapolated); a solution
pressing on a window's edge is re-solved with that window moved (:func:`solve_windowed`). At a
solution the lifted values equal the transcription of χ (``problem.py``; λ = G⁺ rhs).

Constraint groups g (CHAPTER5_NOTES §1.9 with the corrections of §3; the first six define C, Q and Λ):

    continuity  the segment coefficients make periodic C3 / C2 splines    (5.14–5.23)
    splines     Q's y, ẏ, ÿ, ŝ = the splines at the instants              (5.10–5.12)
    dynamics    rhs = M ÿ + k − g − Q_p − R f_m                           (5.1)
    paths       l_m, v_m = the muscle paths at (y, ẏ)                     (A.9)
    activation  a·F_max·g(l_ce, v_ce) = f_ce: the activation that makes F  (2.18, 4.18)
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
    hip_bound   |hip moment| ≤ bound at every instant, a tighter one in swing (opt-in, PredictSettings)
    windows     each instant inside its window of segments
    monotone    dτ_s/dy ≤ 0 at the sampled ankle angles of ``monotone_range_rad`` (prosthetic models; linear in D)

Status (nn = 18, from :func:`initial_guess`, one core shared with a second solve): the symmetric
model with windows of ±3 segments reaches IPOPT's optimum in one solve (``gait predict``: 468 iterations,
J 7.953, 382 s; 1.00 and 1.33 m/s: 362 and 368 iterations; against the bundled reference of 2026-12-04, the
normative trial's: 232 iterations, J 9.876, 172 s alone; against the crouched walk's of 2026-12-03 it took 1072,
``benchmarks/bench_predict.py``). Narrower windows are cheaper per iteration but each solve is confined (instants
cannot cross nodes) and the chain of re-centred solves ends in worse optima (J 12.5–14.0) or infeasible; the full
model with ±2 segments was at J 19.9 after 190 iterations. Of each iteration, 55–65 ms go into the
exact Hessian and 5 ms into the Jacobian; the rest is MUMPS (METIS ordering 0.44 s per iteration for
the full model with ±0, default ordering 0.6 s, AMD 2.2 s): the KKT factor has 6–7 million entries,
because every instant couples the coefficients of all 25 splines over its window.
Earlier, with χ's splines evaluated directly (only the physics lifted), the full model reached J 8.042
after 336 iterations in 419 s plus 98 s to build the Hessian.

Bounds: the nodal values p_{k,0}, durations and steps as :func:`box_bounds`; ŝ ≥ 0 (a taut or just
slack tendon, §3 item 18) and 0 ≤ a ≤ 1.
Cost J = w1·Et/100 + w2·Jdev (5.29) with the heat rate's kinks smoothed for the optimiser as in
EID (reported costs use the exact model).
"""

from __future__ import annotations

import time
from collections import OrderedDict
from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.core.interrupts import interrupts_raised
from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.predict.constraints import GAIT_SHAPE, clearance_phases, feet_in_contact, friction, smooth_max
from gaitcli.predict.cost import cost_of_transport, deviation
from gaitcli.predict.grid import instant_times, periodic_derivative
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout, box_bounds, half_cycle_intervals
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import CYCLE_PCT, VARIABLES, Reference
from gaitcli.predict.settings import TIME_LIMIT_STATUS, PredictSettings
from gaitcli.predict.splines import PeriodicSpline, continuity_matrix, quartic, segment_of, window_values

#: re-exported for the call sites until they import settings.py, layout.py and guess.py
__all__ = ["NLP", "PredictSettings", "TIME_LIMIT_STATUS", "box_bounds", "build_nlp", "cached_nlp", "initial_guess",
           "instant_segments", "moved_windows", "solve", "solve_windowed", "solver_for"]

GRAVITY_M_S2 = 9.81
REACTION_SCALE_N = 100.0
DURATION_SCALE_S = 0.1
#: scale of each lifted quantity (its variables are value/scale)
LIFTED_SCALE = {"y": 1.0, "yd": 3.0, "ydd": 30.0, "stretch": 1.0, "rhs": 100.0, "l_m": 1.0, "v_m": 1.0, "a": 1.0}
#: the lifted blocks: (name, rows: "instants" or "half", [(quantity, columns)])
FULL_LIFTED = (("Q", "instants", (("y", 9), ("yd", 9), ("ydd", 9), ("stretch", 16), ("rhs", 9), ("l_m", 16),
                                  ("v_m", 16), ("a", 16))),)
SYMMETRIC_LIFTED = (("Q", "instants", (("y", 3), ("yd", 3), ("ydd", 3), ("stretch", 8), ("l_m", 8), ("v_m", 8),
                                       ("a", 8))),
                    ("P", "half", (("y", 3), ("yd", 3), ("ydd", 3), ("rhs", 9))))
#: scale of the device coefficients a_p, b_p, c0, a_n, b_n (N·m/rad³, /rad², /rad) and d_prosth (N·m·s/rad)
DEVICE_SCALE = np.array([1e4, 1e3, 1e2, 1e3, 1e3, 1.0])
#: bounds of the optimal prosthesis's coefficients: they contain Table A.7's feet and Table A.8's optima;
#: c0 ≤ 0 (a restoring spring), 0 ≤ d_prosth ≤ 2 (CHAPTER5_NOTES §3 item 16)
DEVICE_BOUNDS = (np.array([-6e4, -1.2e4, -500.0, -1e4, -2e3, 0.0]), np.array([6e4, 1.2e4, 0.0, 1e4, 8e3, 2.0]))


@dataclass
class SplineBlock:
    """One spline family of w: its coefficients (``rows`` × ``columns`` SX), spline, the χ block it stands for."""

    name: str
    spline: PeriodicSpline
    coefficients: ca.SX
    design_block: str


@dataclass
class NLP:
    """The symbolic problem (module docstring): w, J(w), g(w) with bounds, per-group slices of g, box bounds on w.

    ``segments`` (name → per-instant segment index) are where each spline family's windows were placed;
    ``values`` maps w's spline part to the gait (durations (8,), L_r, L_l, y, ẏ, ÿ, ŝ at the I instants,
    the full model's 9 coordinates and 16 muscles) that :meth:`Transcriber.at` transcribes; ``parts`` holds
    Et and Jdev as expressions of w.
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
    layout: DesignLayout
    splines: list
    segments: dict
    reach: int
    values: ca.Function
    lifted: tuple
    parameters: ca.SX = field(default_factory=lambda: ca.SX.sym("p", 0))
    device_size: int = 0
    parts: dict = field(default_factory=dict)
    solvers: dict = field(default_factory=dict)  # the compiled IPOPT solvers by their options (solver_for)
    #: ∇J, the Jacobian of g and the Hessian of the Lagrangian as CasADi made them for the first solver
    #: (solver_for): every later solver of this NLP (other IPOPT options) takes them instead of deriving anew
    derivatives: dict = field(default_factory=dict)

    def parameter_values(self, settings: PredictSettings) -> np.ndarray:
        """p = (v, w1, w2) of ``settings``."""
        return settings.parameter_values()

    def device_bounds(self, curve=None) -> tuple[np.ndarray, np.ndarray]:
        """Bounds on D: fixed at ``curve``'s coefficients (a ProsthesisCurve), or the optimal prosthesis's box."""
        if curve is None:
            return DEVICE_BOUNDS[0] / DEVICE_SCALE, DEVICE_BOUNDS[1] / DEVICE_SCALE
        c = curve.coefficients() / DEVICE_SCALE
        return c, c

    def bounds(self, curve=None) -> tuple[np.ndarray, np.ndarray]:
        """lbw, ubw with D fixed at ``curve`` (or free for the optimal prosthesis when ``curve`` is None)."""
        if not self.device_size:
            return self.lbw, self.ubw
        low, high = self.device_bounds(curve)
        return np.concatenate([self.lbw, low]), np.concatenate([self.ubw, high])

    def constraint_values(self, w, settings: PredictSettings | None = None) -> np.ndarray:
        """g(w) at the parameters of ``settings``."""
        f = ca.Function("g", [self.w, self.parameters], [self.constraints])
        return np.array(f(np.asarray(w, float), self.parameter_values(settings or PredictSettings()))).ravel()

    def cost_parts(self, w, settings: PredictSettings | None = None) -> tuple[float, float, float]:
        """(J, Et, Jdev) of w at the parameters of ``settings`` (the optimiser's smoothed heat rates)."""
        f = ca.Function("f", [self.w, self.parameters], [self.cost, self.parts["Et"], self.parts["Jdev"]])
        out = f(np.asarray(w, float), self.parameter_values(settings or PredictSettings()))
        return tuple(float(v) for v in out)

    def device(self, w) -> np.ndarray:
        """The device coefficients (a_p, b_p, c0, a_n, b_n, d_prosth) of w (empty without a device)."""
        w = np.asarray(w, float).ravel()
        return w[w.size - self.device_size:] * DEVICE_SCALE if self.device_size else np.zeros(0)

    @property
    def spline_size(self) -> int:
        """Length of w's first part: the segment coefficients, durations and step lengths."""
        return sum(b.coefficients.numel() for b in self.splines) + self.layout.blocks["durations"][1] + \
            self.layout.blocks["steps"][1]

    def coefficients_of(self, x: np.ndarray) -> np.ndarray:
        """w's spline part for χ ``x``: the segment coefficients of its splines, durations, steps."""
        blocks = self.layout.unpack(np.asarray(x, float))
        parts = [(b.spline.matrix @ blocks[b.design_block]).ravel(order="F") for b in self.splines]
        return np.concatenate(parts + [blocks["durations"].ravel() / DURATION_SCALE_S, blocks["steps"].ravel()])

    def gait(self, w) -> tuple:
        """(durations (8,), L_r, L_l, (y, ẏ, ÿ, ŝ) at the instants) of w, for :meth:`Transcriber.at`."""
        out = self.values(np.asarray(w, float).ravel()[:self.spline_size])
        durations = np.array(out[0]).ravel()
        return durations, float(out[1]), float(out[2]), tuple(np.array(v) for v in out[3:])

    def start(self, x: np.ndarray, device=None) -> np.ndarray:
        """w for the design vector χ ``x`` (clipped into its box): the coefficients of its splines, the lifted
        values and λ from the transcription of that gait (``problem.py``, λ = G⁺ rhs); D from ``device``
        (a ProsthesisCurve, that of the transcriber's muscles by default). The removed muscles' values are 0."""
        low, high = box_bounds(self.layout, self.transcriber.muscles.present)
        head = self.coefficients_of(np.clip(x, low, high))
        t = self.transcriber.at(*self.gait(head))
        grid = self.transcriber.grid
        opening = grid.instant_points
        full = {"y": t.y[opening], "yd": t.yd[opening], "ydd": t.ydd[opening], "stretch": t.stretch[opening],
                "rhs": np.vstack(t.generalized_forces)[opening], "l_m": t.muscle_lengths_m,
                "v_m": t.muscle_velocities_m_s, "a": np.clip(t.muscle_state["a"], 0.0, 1.0)}
        parts = [head]
        for _, rows, quantities in self.lifted:
            block = []
            for name, cols in quantities:
                v = full[name][:grid.instants // 2] if rows == "half" else full[name]
                if self.layout.symmetric and name in ("y", "yd", "ydd"):
                    v = v[:, :3] if rows == "half" else v[:, 3:6]
                elif self.layout.symmetric and rows != "half":
                    v = v[:, :cols]
                block.append(v / LIFTED_SCALE[name])
            parts.append(np.nan_to_num(np.column_stack(block)).ravel(order="F"))
        points = grid.points // 2 if self.layout.symmetric else grid.points
        parts.append(np.concatenate(t.reactions[:points]) / REACTION_SCALE_N)
        w = np.concatenate(parts)
        w[:self.lbw.size] = np.where(self.lbw == self.ubw, self.lbw, w[:self.lbw.size])  # removed muscles: 0
        if self.device_size:
            curve = device if device is not None else self.transcriber.muscles.prosthesis
            w = np.concatenate([w, curve.coefficients() / DEVICE_SCALE])
        return w

    def design(self, w) -> np.ndarray:
        """χ of w: the nodal values p_{k,0} (5.13), durations and step lengths."""
        w = np.asarray(w, float).ravel()
        blocks, start = {}, 0
        for b in self.splines:
            rows, cols = b.coefficients.shape
            c = w[start:start + rows * cols].reshape(rows, cols, order="F")
            blocks[b.design_block] = c[0::b.spline.degree + 1]
            start += rows * cols
        n_d = self.layout.blocks["durations"][1]
        blocks["durations"] = w[start:start + n_d] * DURATION_SCALE_S
        blocks["steps"] = w[start + n_d:start + n_d + self.layout.blocks["steps"][1]]
        return self.layout.pack(blocks)

    def segments_hold(self, x: np.ndarray) -> bool:
        """Whether every instant of χ ``x`` lies in its windows (then the solution is the splines')."""
        now = instant_segments(self.transcriber, self.layout, x)
        return all(np.all(np.abs(now[k] - self.segments[k]) <= self.reach) for k in self.segments)


#: the NLPs built in this process (with their compiled solvers), most recently used last (cached_nlp)
_BUILT: OrderedDict = OrderedDict()
#: how many NLPs stay built: a study alternates between at most two structures (intact, prosthetic)
BUILT_NLPS_KEPT = 3


def cached_nlp(transcriber: Transcriber, reference: Reference, settings: PredictSettings | None = None, *,
               symmetric: bool = False, segments: dict, reach: int | None = None) -> NLP:
    """:func:`build_nlp`, built once per process for each structure: the subject's model and muscles, node
    count, grid, reference, the settings that shape the problem (not speed, weights or IPOPT's stopping
    rules: parameters and solver options), the windows. A study's cases at other speeds or weight sets, and
    every commercial foot, reuse one problem and its compiled solvers (:func:`solver_for`)."""
    s = settings or PredictSettings()
    reach = s.window_reach if reach is None else reach
    key = (transcriber.key, reference.digest(), repr(s.structure()), symmetric, reach, tuple((k, tuple(int(i) for i in v)) for k, v in sorted(segments.items())))
    if key in _BUILT:
        _BUILT.move_to_end(key)
    else:
        _BUILT[key] = build_nlp(transcriber, reference, s, symmetric=symmetric, segments=segments, reach=reach)
        while len(_BUILT) > BUILT_NLPS_KEPT:
            _BUILT.popitem(last=False)
    nlp = _BUILT[key]
    nlp.transcriber = transcriber  # the same structure; this transcriber's prosthesis is the device's start
    return nlp


def instant_segments(transcriber: Transcriber, layout: DesignLayout, x: np.ndarray) -> dict:
    """The spline segment of each instant of χ ``x``: "cycle" (I,) for the T-periodic splines and, in the
    symmetric model, "half" (I/2,) for the T/2-periodic trunk splines."""
    durations = layout.phase_durations(x)
    fractions = instant_times(transcriber.grid, durations) / durations.sum()
    out = {"cycle": segment_of(transcriber.quartic, fractions)}
    if layout.symmetric:
        half = transcriber.grid.instants // 2
        out["half"] = segment_of(_half_spline(layout), 2 * fractions[:half])
    return out


def _half_spline(layout: DesignLayout) -> PeriodicSpline:
    """The trunk's T/2-periodic quartic of the symmetric model (N_h odd intervals)."""
    return quartic(half_cycle_intervals(layout.nodes - 1) + 1)


def _interpolants(table: np.ndarray) -> list[ca.Function]:
    """Linear interpolants over the cycle (%) of a reference table's columns (101 × 10)."""
    return [ca.interpolant(f"reference_{k}", "linear", [CYCLE_PCT], table[:, k]) for k in range(len(VARIABLES))]


def _mirror(row):
    """A 9-vector of generalized forces (or coordinates' rates) with the legs swapped."""
    return ca.vertcat(row[0:3], row[6:9], row[3:6])


def build_nlp(transcriber: Transcriber, reference: Reference, settings: PredictSettings | None = None, *,
              symmetric: bool = False, segments: dict | None = None, reach: int | None = None) -> NLP:
    """The lifted NLP of one prediction (module docstring for the variables and groups), each instant reading
    the spline segments ``segments`` ± ``reach`` (default: where the default guess puts the instants)."""
    s = settings or PredictSettings()
    reach = s.window_reach if reach is None else reach
    layout = DesignLayout.build(transcriber.layout.nodes, symmetric=symmetric)
    if segments is None:
        segments = instant_segments(transcriber, layout, initial_guess(transcriber, reference, s, symmetric=symmetric))
    model, contact, grid, muscles = transcriber.model, transcriber.contact, transcriber.grid, transcriber.muscles
    params = muscles.muscle.params
    n_i, n = grid.instants, layout.nodes - 1
    half = n_i // 2
    quartic_spline, cubic_spline = transcriber.quartic, transcriber.cubic
    sym = ca.SX.sym
    if symmetric:
        half_spline = _half_spline(layout)
        splines = [SplineBlock("trunk", half_spline, sym("Ct", 5 * half_spline.intervals, 3), "trunk"),
                   SplineBlock("leg", quartic_spline, sym("Cy", 5 * n, 3), "right_leg"),
                   SplineBlock("stretch", cubic_spline, sym("Cs", 4 * n, 8), "right_stretch")]
        durations_z, steps = sym("T", 4), sym("L", 1)
        durations = ca.vertcat(durations_z, durations_z) * DURATION_SCALE_S
        steps_r = steps_l = steps[0]
        lifted_blocks, points = SYMMETRIC_LIFTED, list(range(grid.points // 2))
        dynamics_instants, muscle_columns, energy_factor = range(half), slice(0, 8), 2.0
    else:
        splines = [SplineBlock("coordinates", quartic_spline, sym("Cy", 5 * n, 9), "coordinates"),
                   SplineBlock("stretch", cubic_spline, sym("Cs", 4 * n, 16), "tendon_stretch")]
        durations_z, steps = sym("T", 8), sym("L", 2)
        durations = durations_z * DURATION_SCALE_S
        steps_r, steps_l = steps[0], steps[1]
        lifted_blocks, points = FULL_LIFTED, list(range(grid.points))
        dynamics_instants, muscle_columns, energy_factor = range(n_i), slice(0, 16), 1.0
    period, stride = ca.sum1(durations), steps_r + steps_l
    times = instant_times(grid, durations)
    fractions = times / period
    parameters = sym("p", 3)  # v, w1, w2
    present = muscles.present[muscle_columns]
    kept = [k for k in range(8) if present[k]]  # of each leg's 8 muscles, those the model has
    columns = [k for k in range(muscle_columns.stop) if muscles.present[k]]  # of the modelled muscles
    device = sym("D", 6) if muscles.prosthetic else None
    coefficients = device * ca.DM(DEVICE_SCALE) if muscles.prosthetic else ca.DM.zeros(6)

    # lifted variables: block name → quantity → (rows × columns) values (variables × scale)
    lifted_symbols, lifted = [], {}
    for block, rows, quantities in lifted_blocks:
        count = half if rows == "half" else n_i
        q = sym(block, count, sum(c for _, c in quantities))
        lifted_symbols.append(q)
        start = 0
        for name, cols in quantities:
            lifted[(block, name)] = q[:, start:start + cols] * LIFTED_SCALE[name]
            start += cols
    phases = [int(p) + 1 for p in grid.phase]
    widths = [len(contact.reaction_names[phases[j]]) for j in points]
    lam_all = sym("R", sum(widths))
    offsets = np.concatenate([[0], np.cumsum(widths)])
    reactions = {j: lam_all[offsets[k]:offsets[k + 1]] * REACTION_SCALE_N for k, j in enumerate(points)}

    groups: dict[str, list] = {name: [] for name in (
        "continuity", "splines", "dynamics", "paths", "activation", "reactions", "moment", "contact", "unilateral",
        "mtp", "friction", "clearance", "excitation", "speed", "shape", "hip_bound", "windows", "monotone")}
    bounds: dict[str, list] = {name: [] for name in groups}

    def add(name, expression, low, high):
        expression = ca.vec(expression)
        k = expression.size1()
        groups[name].append(expression)
        bounds[name].append((np.broadcast_to(low, (k,)).astype(float), np.broadcast_to(high, (k,)).astype(float)))

    # every instant stays inside its window of segments: its polynomials are never extrapolated (a quartic's
    # ÿ one segment beyond its node is off by 12·Δp4·τ²/Δt²); a solution pressing on a window's edge is
    # re-solved with that window moved on (solve_windowed)
    for key, spline, count, scale in (("cycle", quartic_spline, n_i, 1.0), ("half", None, half, 2.0)):
        if key in segments:
            intervals = (spline or _half_spline(layout)).intervals
            k0 = np.asarray(segments[key], float)
            add("windows", scale * fractions[:count] * intervals - ca.DM(k0), -float(reach), reach + 1.0)

    # the segment coefficients form periodic splines (5.14–5.23); the lifted y, ẏ, ÿ, ŝ are their values
    # (a removed muscle's spline and values are fixed at 0 by their bounds: no rows)
    kept_columns = {b.name: (columns if b.name == "stretch" else list(range(b.coefficients.shape[1])))
                    for b in splines}
    for b in splines:
        add("continuity", ca.DM(continuity_matrix(b.spline)) @ b.coefficients[:, kept_columns[b.name]], 0.0, 0.0)
    drift = stride / period  # hip x: y1 = periodic + (ΔS/T)·t (notes §3 item 4)
    spline_rows = {}  # (family, instant) → [y, ẏ, ÿ] or [ŝ] rows from the splines

    def spline_values(b: SplineBlock, i: int, fraction, span, derivatives):
        key = "half" if b.name == "trunk" else "cycle"
        k = int(segments[key][i])
        return window_values(b.spline, b.coefficients, span, fraction, (k - reach, k + reach), derivatives)

    by_name = {b.name: b for b in splines}
    for i in range(n_i):
        if symmetric:
            leg = spline_values(by_name["leg"], i, fractions[i], period, range(3))
            spline_rows[("leg", i)] = leg + spline_values(by_name["stretch"], i, fractions[i], period, (0,))
            if i < half:
                trunk = spline_values(by_name["trunk"], i, 2 * fractions[i], period / 2, range(3))
                trunk[0][0] += drift * times[i]
                trunk[1][0] += drift
                spline_rows[("trunk", i)] = trunk
        else:
            rows = spline_values(by_name["coordinates"], i, fractions[i], period, range(3))
            rows[0][0] += drift * times[i]
            rows[1][0] += drift
            spline_rows[("coordinates", i)] = rows + spline_values(by_name["stretch"], i, fractions[i], period, (0,))

    def tie(block, i, rows, names):
        for row, name in zip(rows, names):
            keep = columns if name == "stretch" else list(range(row.shape[1]))
            add("splines", (lifted[(block, name)][i, keep] - row[:, keep]) / LIFTED_SCALE[name], 0.0, 0.0)

    for i in range(n_i):
        if symmetric:
            tie("Q", i, spline_rows[("leg", i)], ("y", "yd", "ydd", "stretch"))
            if i < half:
                tie("P", i, spline_rows[("trunk", i)], ("y", "yd", "ydd"))
        else:
            tie("Q", i, spline_rows[("coordinates", i)], ("y", "yd", "ydd", "stretch"))

    # the full cycle's values at every instant (the symmetric model: left = right half a cycle later)
    def full_rows(name):
        if not symmetric:
            return [lifted[("Q", name)][i, :].T for i in range(n_i)]
        out = []
        for i in range(n_i):
            right, left = lifted[("Q", name)][i, :].T, lifted[("Q", name)][(i + half) % n_i, :].T
            if name in ("y", "yd", "ydd"):
                trunk = lifted[("P", name)][i % half, :].T
                if name == "y" and i >= half:
                    trunk = trunk + ca.vertcat(stride / 2, 0, 0)  # y1(t + T/2) = y1(t) + ΔS/2
                out.append(ca.vertcat(trunk, right, left))
            else:
                out.append(ca.vertcat(right, left))
        return out

    value = {name: full_rows(name) for name in ("y", "yd", "ydd", "stretch", "l_m", "v_m", "a")}
    if symmetric:
        rhs = [lifted[("P", "rhs")][i % half, :].T if i < half else _mirror(lifted[("P", "rhs")][i % half, :].T)
               for i in range(n_i)]
    else:
        rhs = [lifted[("Q", "rhs")][i, :].T for i in range(n_i)]
    f_max = np.tile(np.asarray(params.max_isometric_force_N), 2)
    forces = [ca.DM(f_max) * value["stretch"][i] ** 2 for i in range(n_i)]  # F = F_max·ŝ² (2.19)
    for i in dynamics_instants:
        y, yd, ydd = value["y"][i], value["yd"][i], value["ydd"][i]
        physics = (model.mass_matrix(y) @ ydd + model.bias(y, yd) - model.gravity(y) - muscles.tissue(y, yd)
                   - muscles.device(y, yd, coefficients) - muscles.moment_arms(y) @ forces[i])
        add("dynamics", (rhs[i] - physics) / LIFTED_SCALE["rhs"], 0.0, 0.0)
    for i in range(n_i):
        y, yd = value["y"][i], value["yd"][i]
        add("paths", value["l_m"][i][columns] - muscles.lengths(y)[columns], 0.0, 0.0)
        add("paths", value["v_m"][i][columns] - muscles.velocities(y, yd)[columns], 0.0, 0.0)

    # the muscles (one leg's 8 per evaluation): tendon from ŝ, rates by the unequal-step differences, the
    # activation that makes F, excitation bounds, metabolic rates
    def matrix(name):
        return ca.horzcat(*value[name]).T  # (I × 16)

    stretch_m, a_m = matrix("stretch"), matrix("a")
    force_m = ca.horzcat(*forces).T
    slack = np.tile(np.asarray(params.tendon_slack_length_m), 2)
    f_max_n = np.tile(np.asarray(params.max_isometric_force_N), 2)
    l_se = ca.repmat(ca.DM(slack).T, n_i, 1) * (1 + params.tendon_strain_at_max_force * stretch_m)
    v_se = periodic_derivative(l_se, times, period)
    adot = periodic_derivative(a_m, times, period)
    t1 = np.tile(np.asarray(params.activation_t1_per_s), 2)
    t2 = np.tile(np.asarray(params.activation_t2_per_s), 2)
    rate = []
    for k in range(muscle_columns.stop // 8):
        c = slice(8 * k, 8 * k + 8)
        l_ce, v_ce = muscles.muscle.fibre_kinematics(l_se[:, c].T, v_se[:, c].T, matrix("l_m")[:, c].T,
                                                     matrix("v_m")[:, c].T)
        # the root of 4.3.3 is real only above a slowest ȧ, below the feasible ȧ ≥ −t2·a (u ≥ 0, the first
        # excitation bound below); a start beyond it (a neighbouring case's unconverged solution) would make Et
        # NaN and stop IPOPT at iteration 0, so ȧ is raised to that floor (MuscleModel.slowest_activation_rate):
        # u exact and smooth on the feasible set and near it, finite everywhere
        a_rows = a_m[:, c].T
        u = muscles.muscle.excitation(a_rows, ca.fmax(adot[:, c].T, muscles.muscle.slowest_activation_rate(a_rows)))
        f_ce = force_m[:, c].T / ca.repmat(ca.DM(np.cos(params.pennation_rad)), 1, n_i)
        # the activation that makes F, as the fibre's force balance a·F_max·g(l_ce, v_ce) = f_ce (2.18) per
        # F_max: a = f_ce/(F_max·g) (4.18) itself has slopes ∝ 1/g², unbounded where g is small
        f_max = ca.repmat(ca.DM(f_max_n[c]), 1, n_i)
        balance = (muscles.muscle.fibre_force(a_m[:, c].T, l_ce, v_ce) - f_ce) / f_max
        add("activation", balance[kept, :], 0.0, 0.0)
        rate.append(transcriber.metabolic(u, a_m[:, c].T, l_ce, v_ce, f_ce).T[:, kept])
        T1, T2 = ca.repmat(ca.DM(t1[c]).T, n_i, 1), ca.repmat(ca.DM(t2[c]).T, n_i, 1)
        add("excitation", (adot[:, c] + T2 * a_m[:, c])[:, kept], 0.0, np.inf)
        add("excitation", ((1 - a_m[:, c]) * (T1 + T2) - adot[:, c])[:, kept], 0.0, np.inf)

    # per control point: reactions, moment error, contact, ground forces, clearance
    foot_forces = {}  # point → side → (f_x, f_z), N
    foot_split = {}  # point → side → (heel f_z, MTP f_z), N
    joint_map_pinv = ca.DM(transcriber.joint_map_pinv)
    for j in points:
        phase, i = phases[j], int(grid.instant[j])
        y = value["y"][i] + (ca.DM([1.0] + [0.0] * 8) * stride if grid.wraps[j] else 0)
        G = contact.reaction_matrix[phase](y)
        lam = reactions[j]
        e = rhs[i] - G @ lam
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
        foot_forces[j] = feet
        foot_split[j] = {side: tuple(sum((lam[k] for k, name in enumerate(names) if name == f"{point}_{side}_fz_N"),
                                         ca.SX(0)) for point in ("heel", "mtp")) for side in ("r", "l")}
        for k, name in enumerate(names):
            if name.endswith("_fz_N"):
                add("unilateral", lam[k], 0.0, np.inf)
            elif name.endswith("_moment_Nm"):
                add("mtp", lam[k], *s.mtp_moment_Nm)
        for side in feet_in_contact(phase):
            add("friction", ca.vertcat(*friction(*feet[side], s.friction_coefficient)), -np.inf, 0.0)
        heights = dict(zip(model.point_names, model.points(y)))
        for point in ("heel_r", "mtp_r", "heel_l", "mtp_l"):
            if phase in clearance_phases(point):
                add("clearance", heights[point][1], s.clearance_m, np.inf)
    add("speed", period - stride / parameters[0], 0.0, 0.0)
    if muscles.prosthetic:  # τ_s decreasing over the declared range (5.3.3): linear in the coefficients
        for angle in np.linspace(*s.monotone_range_rad, s.monotone_samples):
            a3, a2, c0 = ((coefficients[0], coefficients[1]) if angle > 0 else (coefficients[3], coefficients[4])) \
                + (coefficients[2],)
            add("monotone", (3 * a3 * angle ** 2 + 2 * a2 * angle + c0) / DEVICE_SCALE[2], -np.inf, 0.0)
    for name, (index, shape_phases, minimum) in GAIT_SHAPE.items():
        chosen = sorted({int(grid.instant[j]) for j in range(grid.points) if phases[j] in shape_phases})
        add("shape", smooth_max(ca.vertcat(*[value["y"][i][index] for i in chosen])), minimum, np.inf)

    if s.swing_hip_moment_Nm_per_kg > 0 or s.hip_moment_Nm_per_kg > 0:  # opt-in bounds on the hip moments (the
        # symmetric model's left leg is its right leg half a cycle later: bounding both would repeat each row)
        limits = (s.hip_moment_Nm_per_kg or np.inf, s.swing_hip_moment_Nm_per_kg or np.inf)
        for i, j in enumerate(grid.instant_points):
            for thigh, swing in (((3, (7, 8)),) if symmetric else ((3, (7, 8)), (6, (3, 4)))):
                bound = min(limits[0], limits[1] if phases[int(j)] in swing else np.inf) * model.total_mass_kg
                if np.isfinite(bound):
                    y, yd = value["y"][i], value["yd"][i]
                    # on an absolute thigh angle, knee and ankle relative: the muscles' and tissues' hip moment
                    add("hip_bound", (muscles.moment_arms(y) @ forces[i] + muscles.tissue(y, yd))[thigh], -bound,
                        bound)

    # cost: Et (5.27) and Jdev (5.28) at the instants
    et = energy_factor * cost_of_transport(ca.horzcat(*rate), times, period, stride)
    mass = model.total_mass_kg

    def per_side(table, i):
        """``table[point]`` (side → value) at instant i; the symmetric model's second half: the first half's,
        sides swapped."""
        j = int(grid.instant_points[i])
        if j in table:
            return table[j]
        mirrored = table[int(grid.instant_points[i - half])]
        return {"r": mirrored["l"], "l": mirrored["r"]}

    deviation_rows = []
    for i, j in enumerate(grid.instant_points):
        y = value["y"][i]
        angles = [*walker_joint_angles(y[2], y[3], y[4], y[5]), *walker_joint_angles(y[2], y[6], y[7], y[8])]
        feet = per_side(foot_forces, i)
        ground = [feet["r"][0], feet["r"][1], feet["l"][0], feet["l"][1]]
        deviation_rows.append(ca.horzcat(*[angle * 180 / np.pi for angle in angles], *[f / mass for f in ground]))
    pct = 100 * fractions
    means = ca.horzcat(*[f(pct) for f in _interpolants(reference.mean)])
    sds = ca.horzcat(*[f(pct) for f in _interpolants(reference.sd)])
    jdev = deviation(ca.vertcat(*deviation_rows), means, sds, times, period)
    if s.cop_sd_m > 0:
        delta = contact.heel_to_mtp_m
        strikes = {"r": 0.0, "l": ca.sum1(durations[:4])}
        stance = ca.sum1(durations[:6])
        rows = []
        for i, j in enumerate(grid.instant_points):
            phase, split = phases[int(j)], per_side(foot_split, i)
            row = ca.SX(0)
            for side, rolling in (("r", (2, 3, 4)), ("l", (6, 7, 8))):
                if phase in rolling:
                    heel, mtp = split[side]  # heel 0 once it is off (phases 4, 8)
                    progress = (times[i] - strikes[side]) / (0.85 * stance)
                    row = (mtp * delta - (heel + mtp) * delta * progress) / (mass * 9.81)
            rows.append(row)
        jdev = jdev + deviation(ca.vertcat(*rows), ca.DM.zeros(n_i, 1), ca.DM.ones(n_i, 1) * s.cop_sd_m, times,
                                period)
    if s.trunk_rate_sd_deg_s > 0:
        trunk_rate = ca.vertcat(*[value["yd"][i][2] * 180 / np.pi for i in range(n_i)])
        jdev = jdev + deviation(trunk_rate, ca.DM.zeros(n_i, 1), ca.DM.ones(n_i, 1) * s.trunk_rate_sd_deg_s,
                                times, period)
    cost = parameters[1] * et / 100.0 + parameters[2] * jdev  # (5.29), weights checked by check_weights

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

    # bounds: nodal values p_{k,0}, durations and steps as box_bounds; ŝ ≥ 0, 0 ≤ a ≤ 1
    low, high = box_bounds(layout, muscles.present)
    blocks_low, blocks_high = layout.unpack(low), layout.unpack(high)
    if s.step_m > 0:
        blocks_low["steps"] = blocks_high["steps"] = np.full_like(blocks_low["steps"], s.step_m)
    lbw, ubw = [], []
    for b in splines:
        width = b.spline.degree + 1
        lo, hi = np.full(b.coefficients.shape, -np.inf), np.full(b.coefficients.shape, np.inf)
        lo[0::width], hi[0::width] = blocks_low[b.design_block], blocks_high[b.design_block]
        if b.name == "stretch":  # a removed muscle's spline is 0
            lo[:, ~present], hi[:, ~present] = 0.0, 0.0
        lbw.append(lo.ravel(order="F"))
        ubw.append(hi.ravel(order="F"))
    lbw += [blocks_low["durations"].ravel() / DURATION_SCALE_S, blocks_low["steps"].ravel()]
    ubw += [blocks_high["durations"].ravel() / DURATION_SCALE_S, blocks_high["steps"].ravel()]
    for (block, rows, quantities), q in zip(lifted_blocks, lifted_symbols):
        lo, hi = [], []
        for name, cols in quantities:
            lo.append(np.full((q.size1(), cols), 0.0 if name in ("stretch", "a") else -np.inf))
            hi.append(np.full((q.size1(), cols), 1.0 if name == "a" else np.inf))
            if name in ("stretch", "l_m", "v_m", "a"):  # a removed muscle's values are fixed at 0
                lo[-1][:, ~muscles.present[:cols]] = hi[-1][:, ~muscles.present[:cols]] = 0.0
        lbw.append(np.hstack(lo).ravel(order="F"))
        ubw.append(np.hstack(hi).ravel(order="F"))
    lbw.append(np.full(lam_all.size1(), -np.inf))
    ubw.append(np.full(lam_all.size1(), np.inf))

    head = ca.vertcat(*[ca.vec(b.coefficients) for b in splines], durations_z, steps)
    full_values = []
    for r, name in enumerate(("y", "yd", "ydd")):
        if symmetric:
            rows = []
            for i in range(n_i):
                trunk = spline_rows[("trunk", i % half)][r]
                if r == 0 and i >= half:
                    trunk = trunk + ca.horzcat(stride / 2, 0, 0)
                rows.append(ca.horzcat(trunk, spline_rows[("leg", i)][r], spline_rows[("leg", (i + half) % n_i)][r]))
        else:
            rows = [spline_rows[("coordinates", i)][r] for i in range(n_i)]
        full_values.append(ca.vertcat(*rows))
    if symmetric:
        full_values.append(ca.vertcat(*[ca.horzcat(spline_rows[("leg", i)][3], spline_rows[("leg", (i + half) % n_i)][3])
                                        for i in range(n_i)]))
    else:
        full_values.append(ca.vertcat(*[spline_rows[("coordinates", i)][3] for i in range(n_i)]))
    values = ca.Function("gait_values", [head], [durations, steps_r, steps_l, *full_values])
    w = ca.vertcat(head, *[ca.vec(q) for q in lifted_symbols], lam_all, *([device] if muscles.prosthetic else []))
    return NLP(w=w, cost=cost, constraints=ca.vertcat(*exprs), lbg=np.concatenate(lows), ubg=np.concatenate(highs),
               groups=slices, lbw=np.concatenate(lbw), ubw=np.concatenate(ubw), transcriber=transcriber,
               layout=layout, splines=splines, segments=segments, reach=reach, values=values,
               lifted=lifted_blocks, parameters=parameters, device_size=6 if muscles.prosthetic else 0,
               parts={"Et": et, "Jdev": jdev})


class IterationReport(ca.Callback):
    """IPOPT's iteration callback: ``report(iteration, objective, constraint_violation)`` after each iteration
    (the violation is the largest distance of g from its bounds); past ``deadline`` (time.perf_counter's clock)
    it stops IPOPT, which then returns ``User_Requested_Stop`` (:data:`TIME_LIMIT_STATUS` in the result)."""

    def __init__(self, nlp: NLP, report=None):
        ca.Callback.__init__(self)
        self.report, self.lbg, self.ubg, self.iteration, self.deadline = report, nlp.lbg, nlp.ubg, 0, None
        self.sizes = {"x": nlp.w.size1(), "g": nlp.constraints.size1()}
        self.construct("iteration_report", {"enable_fd": False})

    def get_n_in(self):
        return ca.nlpsol_n_out()

    def get_n_out(self):
        return 1

    def get_name_in(self, i):
        return ca.nlpsol_out(i)

    def get_name_out(self, i):
        return "ret"

    def get_sparsity_in(self, i):
        name = ca.nlpsol_out(i)
        if name in ("f",):
            return ca.Sparsity.scalar()
        if name in ("x", "lam_x"):
            return ca.Sparsity.dense(self.sizes["x"])
        if name in ("g", "lam_g"):
            return ca.Sparsity.dense(self.sizes["g"])
        return ca.Sparsity(0, 0)

    def start(self, report, deadline: float | None = None) -> None:
        """Report to ``report`` (or nobody) from iteration 0, and stop past ``deadline``: the compiled solver
        keeps this callback."""
        self.report, self.iteration, self.deadline = report, 0, deadline

    def eval(self, arg):
        stop = int(self.deadline is not None and time.perf_counter() > self.deadline)
        if self.report is None:
            return [stop]
        g = np.array(arg[ca.nlpsol_out().index("g")]).ravel()
        violation = float(np.max(np.maximum(self.lbg - g, 0) + np.maximum(g - self.ubg, 0))) if g.size else 0.0
        self.report(self.iteration, float(arg[ca.nlpsol_out().index("f")]), violation)
        self.iteration += 1
        return [stop]


def _ipopt_options(settings: PredictSettings, warm: bool) -> dict:
    s = settings
    opts = {"print_time": False, "ipopt.print_level": s.print_level, "ipopt.sb": "yes",
            "ipopt.max_iter": s.max_iterations, "ipopt.tol": s.tolerance, "ipopt.mu_strategy": "adaptive",
            "ipopt.mumps_pivot_order": 5,  # METIS: the fastest ordering measured on this KKT system
            # MUMPS without its own row/column scaling (IPOPT's defaults 7 and 77): measured at 1.33 m/s, weights
            # b), the normal gait 96 iterations in 31 s (109 in 48 s), SACH 262 in 73 s (363 in 119 s)
            "ipopt.mumps_permuting_scaling": 0, "ipopt.mumps_scaling": 0,
            "ipopt.acceptable_tol": s.acceptable_tolerance, "ipopt.acceptable_iter": s.acceptable_iterations,
            "ipopt.acceptable_obj_change_tol": s.acceptable_objective_change}
    if warm:
        opts.update({"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-6,
                     "ipopt.warm_start_bound_push": 1e-9, "ipopt.warm_start_mult_bound_push": 1e-9})
    return opts


def solver_for(nlp: NLP, settings: PredictSettings, *, warm: bool = False, options: dict | None = None):
    """IPOPT for ``nlp`` with the options of ``settings`` (a warm start's when ``warm``), compiled once per NLP
    and option set and kept on it: the speed and the weights are parameters, so a study's cases reuse it.
    Returns (solver, its iteration callback)."""
    opts = {**_ipopt_options(settings, warm), **(options or {})}
    key = repr(sorted(opts.items()))
    cache = nlp.solvers
    if key not in cache:
        callback = IterationReport(nlp)
        problem = {"x": nlp.w, "f": nlp.cost, "g": nlp.constraints, "p": nlp.parameters}
        exact = opts.get("ipopt.hessian_approximation", "exact") == "exact"
        reuse = nlp.derivatives if exact else {}
        solver = ca.nlpsol("predict", "ipopt", problem, {**opts, **reuse, "iteration_callback": callback})
        if exact and not nlp.derivatives:  # the symbolic Hessian is most of a solver's construction time
            nlp.derivatives = {"grad_f": solver.get_function("nlp_grad_f"), "jac_g": solver.get_function("nlp_jac_g"),
                               "hess_lag": solver.get_function("nlp_hess_l")}
        cache[key] = (solver, callback)
    return cache[key]


def solve(nlp: NLP, x0: np.ndarray, settings: PredictSettings | None = None, *, w0: np.ndarray | None = None,
          multipliers: dict | None = None, options: dict | None = None, report=None, device=None,
          optimal_device: bool = False, deadline: float | None = None) -> dict:
    """IPOPT with exact derivatives (Hessian included) from χ ``x0`` (or the whole ``w0``, and IPOPT's
    ``multipliers`` of an earlier solve for a warm start); returns χ, w, the multipliers, the status,
    iterations and cost. ``options``: further IPOPT/CasADi options; ``report(iteration, objective, violation)``
    is called after every IPOPT iteration. Prosthetic models: D starts at (and, unless ``optimal_device``, is
    fixed at) ``device`` (a ProsthesisCurve; default the transcriber's), free within DEVICE_BOUNDS when
    ``optimal_device``; the result's ``device`` holds the coefficients. Past ``deadline`` (time.perf_counter's
    clock) IPOPT stops with status :data:`TIME_LIMIT_STATUS`, unsuccessful."""
    s = settings or PredictSettings()
    solver, callback = solver_for(nlp, s, warm=bool(multipliers), options=options)
    callback.start(report, deadline)
    start = nlp.start(x0, device) if w0 is None else w0
    if nlp.device_size and device is not None and w0 is not None:  # D starts at the given device
        start = np.concatenate([start[:start.size - nlp.device_size], device.coefficients() / DEVICE_SCALE])
    fixed = None if optimal_device else (device or nlp.transcriber.muscles.prosthesis)
    lbw, ubw = nlp.bounds(fixed)
    extra = {"lam_g0": multipliers["lam_g"], "lam_x0": multipliers["lam_x"]} if multipliers else {}
    with interrupts_raised():
        result = solver(x0=np.clip(start, lbw, ubw), lbx=lbw, ubx=ubw, lbg=nlp.lbg, ubg=nlp.ubg,
                        p=nlp.parameter_values(s), **extra)
    stats = solver.stats()
    w = np.array(result["x"]).ravel()
    status = stats.get("return_status", "")
    if status == "User_Requested_Stop" and deadline is not None and time.perf_counter() > deadline:
        status = TIME_LIMIT_STATUS
    return {"x": nlp.design(w), "w": w, "status": status, "device": nlp.device(w),
            "multipliers": {"lam_g": np.array(result["lam_g"]).ravel(), "lam_x": np.array(result["lam_x"]).ravel()},
            "success": bool(stats.get("success")), "iterations": int(stats.get("iter_count", -1)),
            "cost": float(result["f"])}


def moved_windows(nlp: NLP, multipliers: dict, threshold: float = 1e-8) -> dict | None:
    """The segments with every window whose edge an instant presses on (a non-zero multiplier of its
    ``windows`` row) moved one segment that way; ``None`` when no window binds (a solution of the
    problem without windows)."""
    lam = multipliers["lam_g"][nlp.groups["windows"]]
    moved, start, changed = {}, 0, False
    for key in ("cycle", "half"):
        if key not in nlp.segments:
            continue
        k = np.asarray(nlp.segments[key], int)
        step = np.where(lam[start:start + k.size] > threshold, 1, np.where(lam[start:start + k.size] < -threshold,
                                                                              -1, 0))
        intervals = (nlp.transcriber.quartic if key == "cycle" else _half_spline(nlp.layout)).intervals
        moved[key] = np.clip(k + step, 0, intervals - 1)
        changed |= bool(np.any(moved[key] != k))
        start += k.size
    return moved if changed else None


def solve_windowed(transcriber: Transcriber, reference: Reference, x0: np.ndarray,
                   settings: PredictSettings | None = None, *, symmetric: bool = False, rounds: int = 6,
                   options: dict | None = None, report=None, w0: np.ndarray | None = None, device=None,
                   optimal_device: bool = False, deadline: float | None = None) -> dict:
    """:func:`solve` with the spline windows placed where ``x0`` puts the instants; while a solution presses on
    a window's edge, that window moves on and the problem is solved again from the last solution (warm, with
    its multipliers; at most ``rounds`` solves). Adds ``rounds``, ``windows_hold`` (no window binds) and the last
    ``nlp``. ``w0``: the whole first start (an earlier solution of a problem of the same structure);
    ``device``, ``optimal_device``, ``deadline`` as :func:`solve`. The problems come from :func:`cached_nlp`."""
    layout = DesignLayout.build(transcriber.layout.nodes, symmetric=symmetric)
    segments = instant_segments(transcriber, layout, x0)
    x, w, multipliers, total = x0, w0, None, 0
    for k in range(1, rounds + 1):
        nlp = cached_nlp(transcriber, reference, settings, symmetric=symmetric, segments=segments)
        result = solve(nlp, x, settings, w0=w, multipliers=multipliers, options=options, report=report,
                       device=device, optimal_device=optimal_device, deadline=deadline)
        total += result["iterations"]
        x, w, multipliers = result["x"], result["w"], result["multipliers"]
        segments = moved_windows(nlp, multipliers)
        multipliers["lam_g"][nlp.groups["windows"]] = 0.0  # the moved windows no longer bind
        if segments is None or not result["success"]:
            break
    return {**result, "iterations": total, "rounds": k, "windows_hold": segments is None, "nlp": nlp}
