"""The predictive-gait NLP (Diss. 5.2.7–5.2.9): :func:`build_nlp` assembles one problem from its parts.

    variables.py    w: every block, its order, size and units; the symmetric model's mirror image
    dynamics.py     the equations of motion, the muscle paths and inversion, the ground at the control points
    objective.py    J = w1·Et/100 + w2·Jdev (5.29) and the opt-in tracking terms
    constraints.py  each constraint group g (its table of equations) in its own function
    pointwise.py    the per-instant functions' derivatives, built once and scattered into IPOPT's
    solve.py        IPOPT through ``core/ipopt.py``, the cache of built problems, the window strategy

Each instant reads the spline segments ``segments[i]`` ± ``reach`` only (``windows`` rows keep it there), so
that every constraint touches a few variables; at a solution the lifted values equal the transcription of χ
(``problem.py``; λ = G⁺ rhs). The speed and the weights are parameters p = (v, w1, w2) and a prosthetic
model's device coefficients variables D (fixed by equal bounds for a given foot): one built problem serves a
study's speeds, weight sets and commercial feet.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.predict import constraints as groups
from gaitcli.predict.dynamics import (
    contact_points,
    dynamics_function,
    leg_activations,
    muscle_forces,
    muscle_function,
    path_residuals,
)
from gaitcli.predict.grid import instant_times
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout, box_bounds
from gaitcli.predict.objective import cost_weights, deviation_function, tracking_extras
from gaitcli.predict.pointwise import Placement, derivatives
from gaitcli.predict.problem import Transcriber, gait_at
from gaitcli.predict.settings import TIME_LIMIT_STATUS, PredictSettings
from gaitcli.predict.variables import (
    DURATION_SCALE_S,
    LIFTED_SCALE,
    REACTION_SCALE_N,
    Variables,
    segment_counts,
    spline_functions,
    spline_positions,
)
from gaitcli.signal.bands import Band

__all__ = ["NLP", "TIME_LIMIT_STATUS", "build_nlp", "instant_segments", "nlp_key"]


@dataclass
class NLP:
    """The symbolic problem: w, J(w; p), g(w; p) with bounds, per-group slices of g, box bounds on w.

    ``segments`` (name → per-instant segment index) are where each spline family's windows were placed and
    ``intervals`` their splines' interval counts (:meth:`gait` gives the gait at the I instants that
    :meth:`Transcriber.at` transcribes); ``parts`` holds Et and Jdev as expressions of w; ``blocks`` each
    block of w (``variables.py``) as a slice; ``key`` what makes two built problems the same (:func:`nlp_key`).
    ``transcriber`` is the one it was built for: any of the same ``key`` transcribes its variables alike.
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
    lifted: tuple
    parameters: ca.SX = field(default_factory=lambda: ca.SX.sym("p", 0))
    device_size: int = 0
    device_law: type | None = None
    parts: dict = field(default_factory=dict)
    intervals: dict = field(default_factory=dict)
    blocks: dict = field(default_factory=dict)
    point_functions: list = field(default_factory=list)
    placements: list = field(default_factory=list)
    rest_cost: ca.SX = field(default_factory=lambda: ca.SX(0))
    key: tuple = ()

    def derivatives(self) -> dict[str, ca.Function]:
        """IPOPT's ∇J, the Jacobian of g and the Hessian of the Lagrangian (``pointwise.derivatives``)."""
        return derivatives(self.w, self.parameters, self.constraints, self.cost, self.rest_cost,
                           self.point_functions, self.placements)

    def parameter_values(self, settings: PredictSettings) -> np.ndarray:
        """p = (v, w1, w2) of ``settings``: the speed (5.43) and the weights (5.29)."""
        return settings.parameter_values()

    def device_bounds(self, curve=None) -> tuple[np.ndarray, np.ndarray]:
        """Bounds on D: fixed at ``curve``'s coefficients (a device of the problem's law), or the optimal
        prosthesis's box (the law's BOUNDS)."""
        law = self.device_law
        if curve is None:
            return law.BOUNDS[0] / law.SCALE, law.BOUNDS[1] / law.SCALE
        if type(curve) is not law:
            raise ValueError(f"a {curve.law} device in a problem built for the {law.law} law")
        c = curve.scaled()
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
        """The device coefficients of w in its law's order (empty without a device)."""
        w = np.asarray(w, float).ravel()
        return w[w.size - self.device_size:] * self.device_law.SCALE if self.device_size else np.zeros(0)

    @property
    def spline_size(self) -> int:
        """Length of w's first part: the B-spline coefficients, durations and step lengths."""
        return sum(b.variables.numel() for b in self.splines) + self.layout.blocks["durations"][1] + \
            self.layout.blocks["steps"][1]

    def coefficients_of(self, x: np.ndarray) -> np.ndarray:
        """w's spline part for χ ``x``: the B-spline coefficients of its splines, durations, steps."""
        blocks = self.layout.unpack(np.asarray(x, float))
        parts = [b.spline.bspline_of(blocks[b.design_block]).ravel(order="F") for b in self.splines]
        return np.concatenate(parts + [blocks["durations"].ravel() / DURATION_SCALE_S, blocks["steps"].ravel()])

    def gait(self, w) -> tuple:
        """(durations (8,), L_r, L_l, (y, ẏ, ÿ, ŝ) at the instants) of w, for :meth:`Transcriber.at`: its χ's
        splines evaluated there (``problem.gait_at``; inside their windows, the windowed polynomials are the
        splines themselves)."""
        x = self.design(w)
        return gait_at(self.layout, x, instant_times(self.transcriber.grid, self.layout.phase_durations(x)))

    def start(self, x: np.ndarray, device=None, transcriber: Transcriber | None = None) -> np.ndarray:
        """w for the design vector χ ``x`` clipped into its box, with the activations clipped into [0, 1]:
        :meth:`lifted_start` of a start that needs no check (a stored solution, an evaluated design)."""
        x = np.clip(x, *box_bounds(self.layout, (transcriber or self.transcriber).muscles.present))
        return self.lifted_start(x, device, transcriber, activation_range=(0.0, 1.0))

    def lifted_start(self, x: np.ndarray, device=None, transcriber: Transcriber | None = None, *,
                     activation_range: tuple[float, float] | None = None) -> np.ndarray:
        """w for χ ``x`` (inside its box): the coefficients of its splines, the lifted values and λ from
        ``transcriber``'s (default the NLP's) transcription of that gait (``problem.py``, λ = G⁺ rhs); the
        activations as transcribed (or clipped into ``activation_range``), undefined values 0; D from
        ``device`` (a ProsthesisLaw, that of the transcriber's muscles by default). The removed muscles'
        values are 0."""
        transcriber = transcriber or self.transcriber
        head = self.coefficients_of(x)
        t = transcriber.at(*self.gait(head))
        grid = transcriber.grid
        opening = grid.instant_points
        a = t.muscle_state["a"] if activation_range is None else np.clip(t.muscle_state["a"], *activation_range)
        full = {"y": t.y[opening], "yd": t.yd[opening], "ydd": t.ydd[opening], "stretch": t.stretch[opening],
                "rhs": np.vstack(t.generalized_forces)[opening], "l_m": t.muscle_lengths_m,
                "v_m": t.muscle_velocities_m_s, "a": a}
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
            curve = device if device is not None else transcriber.muscles.prosthesis
            w = np.concatenate([w, curve.scaled()])
        return w

    def design(self, w) -> np.ndarray:
        """χ of w: the nodal values p_{k,0} (5.13), durations and step lengths."""
        w = np.asarray(w, float).ravel()
        blocks, start = {}, 0
        for b in self.splines:
            rows, cols = b.variables.shape
            c = w[start:start + rows * cols].reshape(rows, cols, order="F")
            blocks[b.design_block] = b.spline.nodal_from_bspline @ c
            start += rows * cols
        n_d = self.layout.blocks["durations"][1]
        blocks["durations"] = w[start:start + n_d] * DURATION_SCALE_S
        blocks["steps"] = w[start + n_d:start + n_d + self.layout.blocks["steps"][1]]
        return self.layout.pack(blocks)

    def segments_hold(self, x: np.ndarray) -> bool:
        """Whether every instant of χ ``x`` lies in its windows (then the solution is the splines')."""
        now = instant_segments(self.transcriber, self.layout, x)
        return all(np.all(np.abs(now[k] - self.segments[k]) <= self.reach) for k in self.segments)


def instant_segments(transcriber: Transcriber, layout: DesignLayout, x: np.ndarray) -> dict:
    """The spline segment of each instant of χ ``x`` on each segment list (``variables.spline_positions``):
    "cycle" (I,) for the T-periodic splines; the symmetric model's "half" (I/2,) for its T/2-periodic trunk;
    the full model's "trunk" and "left" (I,)."""
    durations = layout.phase_durations(x)
    fractions = instant_times(transcriber.grid, durations) / durations.sum()
    intervals = segment_counts(layout)
    return {key: np.clip(np.floor(position), 0, intervals[key] - 1).astype(int)
            for key, position in spline_positions(layout, fractions).items()}


def nlp_key(transcriber: Transcriber, reference: Band, settings: PredictSettings, *, symmetric: bool,
            segments: dict, reach: int) -> tuple:
    """What makes two problems the same: the subject's model and muscles, node count and grid
    (``Transcriber.key``), the reference, the settings that shape the problem (not speed, weights or IPOPT's
    stopping rules: parameters and solver options, ``PredictSettings.structure``), the windows."""
    windows = tuple((k, tuple(int(i) for i in v)) for k, v in sorted(segments.items()))
    return (transcriber.key, reference.digest(), repr(settings.structure()), symmetric, reach, windows)


def build_nlp(transcriber: Transcriber, reference: Band, settings: PredictSettings | None = None, *,
              symmetric: bool = False, segments: dict | None = None, reach: int | None = None) -> NLP:
    """The lifted NLP of one prediction (module docstring).

    Parameters
    ----------
    transcriber : Transcriber
        The subject's model, muscles (a prosthetic model's included), node count and control grid.
    reference : Band
        What Jdev (5.28) tracks.
    settings : PredictSettings, optional
        What shapes the problem (tolerances, opt-in terms); its speed and weights are the parameters p, not
        part of the problem.
    symmetric : bool
        The symmetric model (5.3.1) or the full one.
    segments : dict, optional
        Each instant's window centre (:func:`instant_segments`; default where the default guess puts them).
    reach : int, optional
        Segments either side of the centre an instant may read (default ``settings.window_reach``).

    Returns
    -------
    NLP
        w, J(w; p), g(w; p) with bounds, each group's slice of g, the bounds on w.
    """
    s = settings or PredictSettings()
    reach = s.window_reach if reach is None else reach
    layout = DesignLayout.build(transcriber.layout.nodes, symmetric=symmetric)
    if segments is None:
        guess = np.clip(initial_guess(transcriber, reference, s, symmetric=symmetric), *box_bounds(layout))
        segments = instant_segments(transcriber, layout, guess)
    v = Variables(transcriber, layout)
    points = contact_points(v, transcriber.contact)
    functions = point_functions(v, transcriber, reference, points)
    rows = constraint_rows(v, transcriber, s, functions, points, segments, reach)
    extras = tracking_extras(v, points, s, transcriber)
    lbw, ubw = v.bounds(transcriber.muscles.present, s.step_m, s.step_range_m)
    g, lbg, ubg, slices, placements = _stacked(rows)
    rest_cost = functions["deviation"].weight * extras
    cost = functions["muscles"].cost + functions["deviation"].cost + rest_cost
    return NLP(w=v.w, cost=cost, constraints=g, lbg=lbg, ubg=ubg, groups=slices, lbw=lbw, ubw=ubw,
               transcriber=transcriber, layout=layout, splines=v.splines, segments=segments, reach=reach,
               lifted=v.lifted_blocks,
               parameters=v.parameters, device_size=0 if v.device is None else v.device.numel(),
               device_law=v.device_law,
               parts={"Et": functions["muscles"].total, "Jdev": functions["deviation"].total + extras},
               intervals=v.intervals, blocks=v.blocks(), point_functions=_distinct(functions, placements),
               placements=placements, rest_cost=rest_cost,
               key=nlp_key(transcriber, reference, s, symmetric=symmetric, segments=segments, reach=reach))


def point_functions(v: Variables, transcriber: Transcriber, reference: Band, points: list) -> dict:
    """The problem's point functions (``pointwise.py``): the dynamics (5.1), the muscles' inversion with Et's
    shares (5.25–5.27) and Jdev's shares (5.28), weighted in J by (5.29)."""
    et_weight, jdev_weight = cost_weights(v)
    model = transcriber.model
    return {"dynamics": dynamics_function(v, model, transcriber.muscles),
            "muscles": muscle_function(v, transcriber, et_weight),
            "deviation": deviation_function(v, reference, points, model.total_mass_kg, jdev_weight)}


def constraint_rows(v: Variables, transcriber: Transcriber, settings: PredictSettings, functions: dict,
                    points: list, segments: dict, reach: int) -> dict:
    """Each constraint group's :class:`~gaitcli.predict.constraints.Rows` (``constraints.GROUPS``): ``functions``
    (:func:`point_functions`), the stated control points (``dynamics.contact_points``) and the splines'
    windows."""
    s, model, muscles = settings, transcriber.model, transcriber.muscles
    forces = muscle_forces(v, muscles.muscle.params.max_isometric_force_N)
    return {"nodes": groups.nodal_rows(v), "splines": groups.splines_rows(spline_functions(v, segments, reach)),
            "dynamics": groups.dynamics_rows(functions["dynamics"]),
            "paths": groups.paths_rows(path_residuals(v, muscles)),
            "activation": groups.activation_rows(functions["muscles"]),
            "reactions": groups.reactions_rows(points),
            "moment": groups.moment_rows(points, transcriber.joint_map_pinv, s.moment_tolerance_Nm),
            "contact": groups.contact_rows(v, points, transcriber.contact, s.contact_tolerance_m),
            "unilateral": groups.unilateral_rows(points), "mtp": groups.mtp_rows(points, s.mtp_moment_Nm),
            "friction": groups.friction_rows(points, s.friction_coefficient),
            "clearance": groups.clearance_rows(points, model, s.clearance_m),
            "excitation": groups.excitation_rows(v, leg_activations(v, muscles.muscle.params)),
            "speed": groups.speed_rows(v), "shape": groups.shape_rows(v, s.foot_flat_min_pct),
            "hip_bound": groups.hip_bound_rows(v, s, model, muscles, forces),
            "windows": groups.windows_rows(v, segments, reach), "monotone": groups.monotone_rows(v, s)}


def _distinct(functions: dict, placements: list[Placement]) -> list:
    """Every point function of the problem once: those of ``functions`` and those placed in g."""
    out = {id(f): f for f in functions.values()}
    out.update({id(p.function): p.function for p in placements})
    return list(out.values())


def _stacked(rows: dict) -> tuple:
    """g, lbg, ubg, each group's slice of g and where each point function's rows lie: the non-empty groups in
    the order of ``constraints.GROUPS``."""
    exprs, lows, highs, slices, placements, start = [], [], [], {}, [], 0
    for name in groups.GROUPS:
        group = rows[name]
        if not group.expressions:
            continue
        block = ca.vertcat(*group.expressions)
        exprs.append(block)
        lows += group.lows
        highs += group.highs
        slices[name] = slice(start, start + block.size1())
        placements += [Placement(function, output, start + first) for function, output, first in group.points]
        start += block.size1()
    return ca.vertcat(*exprs), np.concatenate(lows), np.concatenate(highs), slices, placements
