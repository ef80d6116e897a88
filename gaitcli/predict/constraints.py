"""The constraint groups of the predictive-gait NLP (Diss. 5.2.8–5.2.9), each built by its own function.

Every group function returns :class:`Rows` (expressions with their lower and upper bounds, in order);
:func:`gaitcli.predict.nlp.build_nlp` stacks them in the order of :data:`GROUPS`. After ``nodes``, the first
five define the lifted variables (``variables.py``) from the splines' B-spline coefficients (periodic C3 / C2
splines by construction, 5.14–5.23, so no continuity rows); the rest are the dissertation's:

    nodes       the nodal values p_{k,0} inside their box                 (5.13; ``layout.box_bounds``)
    splines     Q's y, ẏ, ÿ, ŝ = the splines at the instants              (5.10–5.12)
    dynamics    rhs = M ÿ + k − g − Q_p − R f_m                           (5.1)
    paths       l_m, v_m = the muscle paths at (y, ẏ)                     (A.9)
    activation  a·F_max·g(l_ce, v_ce) = f_ce: the activation that makes F  (2.18, 4.18)
    reactions   G_phᵀ (rhs − G_ph λ) = 0: λ = G_ph⁺ rhs                   (5.30)
    moment      |B⁺e| ≤ εm, e = rhs − G_ph λ, per joint and control point (5.49–5.51, 5.53)
    contact     |c_ph| ≤ εk per row and control point                    (5.57)
    unilateral  f_z ≥ 0 at the points in contact                          (5.37–5.40)
    mtp         −10 ≤ m_B ≤ 0 N·m where a foot stands on B alone          (docs/prediction.md)
    friction    |f_x| ≤ μ f_z per foot down (two linear inequalities)     (5.41–5.42)
    clearance   z ≥ h_min of the points not in contact                    (5.33–5.36)
    excitation  0 ≤ u ≤ 1 as −t2·a ≤ ȧ ≤ (1 − a)(t1 + t2) with 0 ≤ a ≤ 1 (5.32)
    speed       ΣT_ph − ΔS/v = 0                                          (5.43)
    shape       LSE(knee in swing) ≥ 60°, LSE(thigh in late stance) ≥ 5°  (5.45–5.48)
    hip_bound   |hip moment| ≤ bound at every instant, a tighter one in swing (opt-in, PredictSettings)
    windows     each instant inside its window of segments
    monotone    dτ_s/dy ≤ 0 at the sampled ankle angles (prosthetic models; linear in D)

Which contact points each group applies to follows from the phase table
(:data:`gaitcli.predict.contact.PHASE_TABLE`), not from the printed lists, two of which are typos
(docs/prediction.md):

- clearance (5.33–5.36): every heel A and MTP B *not* in contact stays at or above ``h_min`` (default 0 m;
  "r_z > 0" as a closed bound);
- unilateral contact (5.37–5.40): the vertical reaction f_z ≥ 0 at every point in contact;
- friction (5.41–5.42): |f_x| ≤ μ·f_z per foot in contact, as the two smooth linear inequalities
  f_x − μ f_z ≤ 0 and −f_x − μ f_z ≤ 0; μ = 0.8 by default (the dissertation gives none; our choice,
  configurable);
- gait shape (5.45–5.48): in its swing (phases 7–8 right, 3–4 left) a knee flexes at least θ_knee = 60°;
  in late stance (phases 4–6 right, 1, 2, 8 left) a thigh extends at least θ_hip = 5° — the absolute thigh
  angle y4/y7, as the equations say. The non-smooth max over control points becomes the log-sum-exp
  surrogate LSE_β(x) = max x + log Σ exp(β(x − max x))/β, an upper bound within ln(n)/β of the max
  (β = 500 rad⁻¹: ≤ 0.54° for 112 points); the true max is reported; with them (our addition) each heel
  rocker, HS→TC, lasts at least ``foot_flat_min_pct`` of the cycle (docs/prediction.md, "The heel rocker");
- excitation (5.32): 0 ≤ u ≤ 1 is stated on ȧ, linear in the lifted a, by (2.17) solved for u at its ends.

The kernels (:func:`friction`, :func:`smooth_max`, the phase lists) take numpy arrays or CasADi expressions.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.core.validate import number
from gaitcli.predict.contact import PHASE_TABLE, PHASES
from gaitcli.predict.dynamics import ContactPoint, LegActivation
from gaitcli.predict.layout import box_bounds
from gaitcli.predict.pointwise import PointFunction
from gaitcli.predict.splines import is_casadi
from gaitcli.predict.variables import (
    REACTION_SCALE_N,
    Variables,
    spline_positions,
)

CONTACT_POINTS = ("heel_r", "mtp_r", "heel_l", "mtp_l")
FRICTION_COEFFICIENT = 0.8
KNEE_SWING_MIN_RAD = np.radians(60.0)
HIP_EXTENSION_MIN_RAD = np.radians(5.0)
SHAPE_SHARPNESS_PER_RAD = 500.0
#: (5.45–5.48): the coordinate (index into y) and the phases over which its max must reach the bound
GAIT_SHAPE = {"knee_r": (4, (7, 8), KNEE_SWING_MIN_RAD), "knee_l": (7, (3, 4), KNEE_SWING_MIN_RAD),
              "thigh_r": (3, (4, 5, 6), HIP_EXTENSION_MIN_RAD), "thigh_l": (6, (1, 2, 8), HIP_EXTENSION_MIN_RAD)}


def in_contact(point: str) -> tuple[int, ...]:
    """The phases in which ``point`` touches the floor."""
    return tuple(p.number for p in PHASE_TABLE if point in p.points())


def clearance_phases(point: str) -> tuple[int, ...]:
    """The phases in which ``point`` must clear the floor (5.33–5.36)."""
    return tuple(n for n in PHASES if n not in in_contact(point))


def feet_in_contact(phase: int) -> tuple[str, ...]:
    """The sides with a foot on the floor in ``phase`` (the friction constraints, 5.41–5.42 corrected)."""
    points = PHASE_TABLE[phase - 1].points()
    return tuple(side for side in ("r", "l") if any(p.endswith(f"_{side}") for p in points))


def friction(force_x_N, force_z_N, coefficient: float = FRICTION_COEFFICIENT):
    """The two smooth inequalities g ≤ 0 of |f_x| ≤ μ f_z (a foot's summed reactions):
    (f_x − μ f_z, −f_x − μ f_z)."""
    mu = number(coefficient, where="friction_coefficient", low=0.0, low_open=True)
    return force_x_N - mu * force_z_N, -force_x_N - mu * force_z_N


def smooth_max(values, sharpness: float = SHAPE_SHARPNESS_PER_RAD):
    """LSE_β(values): a smooth upper bound of max(values), within ln(n)/β of it."""
    if is_casadi(values):
        x = ca.vec(values)
        top = ca.mmax(x)  # its derivative is that of the active entry: LSE's gradient does not depend on it
        return top + ca.log(ca.sum1(ca.exp(sharpness * (x - top)))) / sharpness
    x = np.asarray(values, float).ravel()
    top = x.max()
    return top + np.log(np.sum(np.exp(sharpness * (x - top)))) / sharpness


# ------------------------------------------------------------------------------------------ the NLP's groups
#: the constraint groups in the order g stacks them (module docstring)
GROUPS = ("nodes", "splines", "dynamics", "paths", "activation", "reactions", "moment", "contact", "unilateral",
          "mtp", "friction", "clearance", "excitation", "speed", "shape", "hip_bound", "windows", "monotone")


@dataclass
class Rows:
    """One constraint group: its expressions (each a column) with their lower and upper bounds, in order."""

    expressions: list = field(default_factory=list)
    lows: list = field(default_factory=list)
    highs: list = field(default_factory=list)
    #: (point function, its output, first row in the group) of the rows that are a point function's
    points: list = field(default_factory=list)

    def add(self, expression, low, high) -> None:
        """Append ``expression``'s entries (column-major) with bounds ``low`` ≤ · ≤ ``high`` (scalars or arrays)."""
        expression = ca.vec(expression)
        k = expression.size1()
        self.expressions.append(expression)
        self.lows.append(np.broadcast_to(low, (k,)).astype(float))
        self.highs.append(np.broadcast_to(high, (k,)).astype(float))

    def add_point(self, function: PointFunction, output: str, low, high) -> None:
        """Append a point function's output at every instant (instant-major) with its bounds."""
        self.points.append((function, output, self.size))
        self.add(function.outputs[output], low, high)

    @property
    def size(self) -> int:
        """How many rows of g the group has."""
        return sum(e.size1() for e in self.expressions)


def windows_rows(v: Variables, segments: dict, reach: int) -> Rows:
    """Every instant inside its window of segments ``segments[key]`` ± ``reach``: its polynomials are never
    extrapolated (a quartic's ÿ one segment beyond its node is off by 12·Δp4·τ²/Δt²); a solution pressing on a
    window's edge is solved again with that window moved on (``solve.solve_windowed``)."""
    rows = Rows()
    positions = spline_positions(v.layout, v.fractions)
    for key in sorted(segments):
        rows.add(positions[key] - ca.DM(np.asarray(segments[key], float)), -float(reach), reach + 1.0)
    return rows


def nodal_rows(v: Variables) -> Rows:
    """The splines' nodal values p_{k,0} (5.13) inside :func:`~gaitcli.predict.layout.box_bounds`' box: linear in
    the B-spline coefficients (d of them per node); a removed muscle's (fixed at 0) has none."""
    rows = Rows()
    blocks_low, blocks_high = (v.layout.unpack(bound) for bound in box_bounds(v.layout))
    for b in v.splines:
        columns, _ = v.family_columns(b)
        nodal = ca.mtimes(ca.DM(b.spline.nodal_from_bspline), b.variables[:, columns])
        rows.add(nodal, blocks_low[b.design_block][:, columns].ravel(order="F"),
                 blocks_high[b.design_block][:, columns].ravel(order="F"))
    return rows


def splines_rows(splines: list[PointFunction]) -> Rows:
    """The lifted y, ẏ, ÿ, ŝ are the splines' values at the instants, scaled (``variables.spline_functions``)."""
    rows = Rows()
    for function in splines:
        rows.add_point(function, "splines", 0.0, 0.0)
    return rows


def dynamics_rows(dynamics: PointFunction) -> Rows:
    """rhs − Φ = 0 (5.1) at the stated instants (``dynamics.dynamics_function``), per 100 N."""
    rows = Rows()
    rows.add_point(dynamics, "dynamics", 0.0, 0.0)
    return rows


def paths_rows(residuals: list) -> Rows:
    """l_m, v_m = the muscle paths (A.9) at every instant (``dynamics.path_residuals``)."""
    rows = Rows()
    for lengths, velocities in residuals:
        rows.add(lengths, 0.0, 0.0)
        rows.add(velocities, 0.0, 0.0)
    return rows


def activation_rows(muscles: PointFunction) -> Rows:
    """The fibre's force balance (2.18) per F_max of every modelled muscle, leg and instant
    (``dynamics.muscle_function``)."""
    rows = Rows()
    rows.add_point(muscles, "activation", 0.0, 0.0)
    return rows


def excitation_rows(v: Variables, legs: list[LegActivation]) -> Rows:
    """0 ≤ u ≤ 1 (5.32) as ȧ + t2·a ≥ 0 and (1 − a)(t1 + t2) − ȧ ≥ 0 of every modelled muscle and instant."""
    rows = Rows()
    for leg in legs:
        rows.add((leg.adot + leg.t2 * leg.a)[:, v.kept], 0.0, np.inf)
        rows.add(((1 - leg.a) * (leg.t1 + leg.t2) - leg.adot)[:, v.kept], 0.0, np.inf)
    return rows


def reactions_rows(points: list[ContactPoint]) -> Rows:
    """G_phᵀ e = 0 at every stated control point: λ = G_ph⁺ rhs (5.30), per 100 N."""
    rows = Rows()
    for p in points:
        rows.add(p.G.T @ p.residual / REACTION_SCALE_N, 0.0, 0.0)
    return rows


def moment_rows(points: list[ContactPoint], joint_map_pinv: np.ndarray, tolerance_Nm: float) -> Rows:
    """|B⁺e| ≤ εm (5.49–5.51, 5.53), N·m, per joint at every stated control point."""
    rows, b_pinv = Rows(), ca.DM(joint_map_pinv)
    for p in points:
        rows.add(b_pinv @ p.residual, -tolerance_Nm, tolerance_Nm)
    return rows


def contact_rows(v: Variables, points: list[ContactPoint], contact, tolerance_m: float) -> Rows:
    """|c_ph| ≤ εk (5.57), m, per row of each stated control point's phase."""
    rows = Rows()
    for p in points:
        rows.add(contact.constraint[p.phase](p.y, v.steps_r, v.steps_l, 0.0), -tolerance_m, tolerance_m)
    return rows


def unilateral_rows(points: list[ContactPoint]) -> Rows:
    """f_z ≥ 0 (5.37–5.40) of every point in contact."""
    rows = Rows()
    for p in points:
        for k, name in enumerate(p.names):
            if name.endswith("_fz_N"):
                rows.add(p.lam[k], 0.0, np.inf)
    return rows


def mtp_rows(points: list[ContactPoint], bounds_Nm: tuple[float, float]) -> Rows:
    """The MTP moment m_B within ``bounds_Nm`` where a foot stands on its MTP point alone."""
    rows = Rows()
    for p in points:
        for k, name in enumerate(p.names):
            if name.endswith("_moment_Nm"):
                rows.add(p.lam[k], *bounds_Nm)
    return rows


def friction_rows(points: list[ContactPoint], coefficient: float) -> Rows:
    """|f_x| ≤ μ f_z (5.41–5.42) per foot down, as :func:`friction`'s two inequalities."""
    rows = Rows()
    for p in points:
        for side in feet_in_contact(p.phase):
            rows.add(ca.vertcat(*friction(*p.feet[side], coefficient)), -np.inf, 0.0)
    return rows


def clearance_rows(points: list[ContactPoint], model, minimum_m: float) -> Rows:
    """z ≥ h_min (5.33–5.36), m, of every contact point not in contact."""
    rows = Rows()
    for p in points:
        heights = dict(zip(model.point_names, model.points(p.y)))
        for point in CONTACT_POINTS:
            if p.phase in clearance_phases(point):
                rows.add(heights[point][1], minimum_m, np.inf)
    return rows


def speed_rows(v: Variables) -> Rows:
    """ΣT_ph − ΔS/v = 0 (5.43), s, with the speed v the NLP's parameter."""
    rows = Rows()
    rows.add(v.period - v.stride / v.parameters[0], 0.0, 0.0)
    return rows


def shape_rows(v: Variables, foot_flat_min_pct: float = 0.0) -> Rows:
    """LSE over the chosen phases' instants of a knee (swing) or a thigh (late stance) ≥ its bound (5.45–5.48);
    each heel rocker (phases 1 and 5, HS→TC) ≥ ``foot_flat_min_pct`` % of the cycle, s (our addition,
    ``PredictSettings.foot_flat_min_pct``; the symmetric model's phase 5 is its phase 1)."""
    rows, grid = Rows(), v.grid
    for index, shape_phases, minimum in GAIT_SHAPE.values():
        chosen = sorted({int(grid.instant[j]) for j in range(grid.points) if v.phases[j] in shape_phases})
        rows.add(smooth_max(ca.vertcat(*[v.values["y"][i][index] for i in chosen])), minimum, np.inf)
    if foot_flat_min_pct > 0:
        for phase in (0,) if v.symmetric else (0, 4):
            rows.add(v.durations[phase] - foot_flat_min_pct / 100 * v.period, 0.0, np.inf)
    return rows


def hip_bound_rows(v: Variables, settings, model, muscles, forces: list) -> Rows:
    """The hip moments of muscles and tissues within ± ``hip_moment_Nm_per_kg`` × body mass at every instant,
    a leg in swing within ± ``swing_hip_moment_Nm_per_kg`` × body mass (opt-in; none when both are 0). The
    symmetric model bounds its right leg alone: its left leg is the same half a cycle later."""
    rows, s = Rows(), settings
    if not (s.swing_hip_moment_Nm_per_kg > 0 or s.hip_moment_Nm_per_kg > 0):
        return rows
    limits = (s.hip_moment_Nm_per_kg or np.inf, s.swing_hip_moment_Nm_per_kg or np.inf)
    for i, j in enumerate(v.grid.instant_points):
        for thigh, swing in (((3, (7, 8)),) if v.symmetric else ((3, (7, 8)), (6, (3, 4)))):
            bound = min(limits[0], limits[1] if v.phases[int(j)] in swing else np.inf) * model.total_mass_kg
            if np.isfinite(bound):
                y, yd = v.values["y"][i], v.values["yd"][i]
                # on an absolute thigh angle, knee and ankle relative: the muscles' and tissues' hip moment
                rows.add((muscles.moment_arms(y) @ forces[i] + muscles.tissue(y, yd))[thigh], -bound, bound)
    return rows


def monotone_rows(v: Variables, settings) -> Rows:
    """dτ_s/dy ≤ 0 (per the law's SLOPE_SCALE; (5.58): 3·a·y² + 2·b·y + c0) at ``monotone_samples`` ankle
    angles of ``monotone_range_rad`` (the prosthetic models' D, 5.3.3: a spring that stiffens, never turns)."""
    rows = Rows()
    if v.device is None:
        return rows
    law = v.device_law
    curve = law.from_values("symbolic", [v.coefficients[k] for k in range(len(law.COEFFICIENTS))])
    for angle in np.linspace(*settings.monotone_range_rad, settings.monotone_samples):
        rows.add(curve.slope_Nm_per_rad(float(angle)) / law.SLOPE_SCALE, -np.inf, 0.0)
    return rows
