"""The design vector χ of the predictive gait (Diss. 5.24) and its symmetric variant (5.3.1).

Full model (``symmetric=False``), N = nn − 1 intervals, N_t = 2·N_h (below) for hip and HAT, signal-major
blocks:

    trunk         N_t × 3  y1 (periodic part), y2, y3: values at the midpoints of N_t intervals over T
                           (quartic; :func:`~gaitcli.predict.splines.quartic_midpoints`)
    right_leg     N × 3    y4 … y6 nodal values (quartic)
    left_leg      N × 3    y7 … y9 nodal values on the left leg's nodes, half a cycle after the right's
    right_stretch N × 8    the right muscles' normalised tendon stretch ŝ (cubic; F = F_max·ŝ²,
                           l_se = l_slack·(1 + ε0·ŝ): docs/prediction.md), nodal values
    left_stretch  N × 8    the left muscles', on the left leg's nodes
    durations     8        T_1 … T_8, s
    steps         2        L_r, L_l, m
    size = 22·N + 3·N_t + 10                                             (438 at nn = 18)

The dissertation puts every signal on the same nn nodes (5.10–5.23). Here each leg has its nn nodes, the
left's starting half a cycle after the right's, and hip and HAT have N_t = 2·N_h intervals: the grid on which
the symmetric model's gait (below) is exactly a point (:func:`full_from_symmetric`), so that the full model
starts from it feasible. N_t is even, where nodal values do not determine a periodic quartic: the trunk's
design values are its values at the intervals' midpoints.

Symmetric model (5.3.1, docs/prediction.md): the left leg is the right leg half a
cycle later, and hip and HAT repeat every half cycle:

    trunk         N_h × 3  y1 (periodic part), y2, y3 over T/2            (quartic, T/2-periodic)
    right_leg     N × 3    y4, y5, y6                                      (quartic, T-periodic)
    right_stretch N × 8    the right muscles' tendon stretch ŝ              (cubic, T-periodic)
    durations     4        T_1 … T_4 (T_5…8 = T_1…4)
    steps         1        L_r (= L_l)
    size = 11·N + 3·N_h + 5                                               (219 at nn = 18)

N_h, the half cycle's number of intervals, must be odd (the periodic quartic is
singular for an even count): the odd number nearest above N/2 (9 for N = 17).
Blocks are stored column-major (``reshape(block, rows, cols)`` in CasADi, Fortran
order in numpy), so each signal's nodal values are contiguous.

Box bounds (:func:`box_bounds`; 5.44 prints none): ranges wide enough for walking, the tendon stretch of a
removed muscle fixed at 0, and no phase so long that its control points lie more than
``grid.MAX_POINT_SPACING_S`` apart.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.predict.grid import MAX_POINT_SPACING_S, PHASE_LENGTH_POINTS
from gaitcli.predict.splines import PeriodicSpline, cubic, evaluation_matrix, is_casadi, quartic, quartic_midpoints

#: box bounds of the nodal values (5.44 prints none: ranges wide enough for walking), per coordinate y1 … y9
COORDINATE_RANGES = ((-0.5, 0.5), (0.5, 1.3), (-0.6, 0.6), (-1.2, 1.0), (0.0, 1.7), (-0.8, 0.8),
                     (-1.2, 1.0), (0.0, 1.7), (-0.8, 0.8))  # hip x (periodic part), hip z, HAT, thigh, knee, ankle
STRETCH_RANGE = (0.0, 1.3)  # F ≤ 1.69 F_max
DURATION_RANGE_S = (0.01, 0.8)
STEP_RANGE_M = (0.2, 1.2)


def half_cycle_intervals(intervals: int) -> int:
    """The odd number of intervals of a half-period spline nearest above ``intervals``/2."""
    half = -(-intervals // 2)
    return half if half % 2 else half + 1


def full_trunk_spline(nodes: int) -> PeriodicSpline:
    """The full model's hip and HAT spline: quartic on 2·N_h intervals over T, designed by its midpoint values."""
    return quartic_midpoints(2 * half_cycle_intervals(nodes - 1))


@dataclass(frozen=True)
class DesignLayout:
    """Where each block of χ lies: ``blocks[name] = (start, rows, columns)``; ``size`` = len(χ)."""

    nodes: int
    symmetric: bool
    blocks: dict[str, tuple[int, int, int]] = field(default_factory=dict)
    size: int = 0

    @classmethod
    def build(cls, nodes: int, *, symmetric: bool = True, coordinates: int = 9, muscles: int = 16) -> DesignLayout:
        """The layout for ``nodes`` (nn; even, see :func:`gaitcli.predict.splines.quartic`)."""
        quartic(nodes)  # the parity check, with its one-line error
        n = nodes - 1
        if symmetric:
            shapes = {"trunk": (half_cycle_intervals(n), 3), "right_leg": (n, (coordinates - 3) // 2),
                      "right_stretch": (n, muscles // 2), "durations": (4, 1), "steps": (1, 1)}
        else:
            leg, side = (coordinates - 3) // 2, muscles // 2
            shapes = {"trunk": (2 * half_cycle_intervals(n), 3), "right_leg": (n, leg), "left_leg": (n, leg),
                      "right_stretch": (n, side), "left_stretch": (n, side), "durations": (8, 1), "steps": (2, 1)}
        blocks, start = {}, 0
        for name, (rows, cols) in shapes.items():
            blocks[name] = (start, rows, cols)
            start += rows * cols
        return cls(nodes=nodes, symmetric=symmetric, blocks=blocks, size=start)

    def unpack(self, x) -> dict:
        """The blocks of χ (numpy (size,) or a CasADi column) as (rows, columns) matrices."""
        out = {}
        for name, (start, rows, cols) in self.blocks.items():
            part = x[start:start + rows * cols]
            out[name] = ca.reshape(part, rows, cols) if is_casadi(x) else \
                np.reshape(np.asarray(part, float), (rows, cols), order="F")
        return out

    def phase_durations(self, x) -> np.ndarray:
        """T_1 … T_8 (s) of a numeric χ (the symmetric model repeats its four)."""
        d = self.unpack(np.asarray(x, float))["durations"].ravel()
        return np.tile(d, 2) if self.symmetric else d

    def step_lengths(self, x) -> tuple[float, float]:
        """(L_r, L_l) in m of a numeric χ (the symmetric model's one step twice)."""
        steps = self.unpack(np.asarray(x, float))["steps"].ravel()
        return (float(steps[0]), float(steps[0])) if self.symmetric else (float(steps[0]), float(steps[1]))

    def pack(self, blocks: dict) -> np.ndarray:
        """χ (size,) from numpy blocks of the layout's shapes (the inverse of :meth:`unpack`)."""
        x = np.zeros(self.size)
        for name, (start, rows, cols) in self.blocks.items():
            value = np.asarray(blocks[name], float).reshape(rows, cols)
            x[start:start + rows * cols] = value.ravel(order="F")
        return x


def box_bounds(layout: DesignLayout, present: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on χ of ``layout`` (full or symmetric); the tendon stretch of muscles not ``present`` (16,) is 0."""
    present = np.ones(16, bool) if present is None else np.asarray(present, bool)
    stretch = tuple(STRETCH_RANGE if keep else (0.0, 0.0) for keep in present)
    ranges = {"trunk": COORDINATE_RANGES[:3], "right_leg": COORDINATE_RANGES[3:6], "left_leg": COORDINATE_RANGES[6:9],
              "right_stretch": stretch[:8], "left_stretch": stretch[8:],
              "durations": (DURATION_RANGE_S,), "steps": (STEP_RANGE_M,)}
    low, high = np.empty(layout.size), np.empty(layout.size)
    for name, (start, rows, cols) in layout.blocks.items():
        per_column = ranges[name] if len(ranges[name]) == cols else ranges[name] * cols
        for k, (lo, hi) in enumerate(per_column):
            low[start + k * rows:start + (k + 1) * rows], high[start + k * rows:start + (k + 1) * rows] = lo, hi
    # no phase so long that its control points lie more than MAX_POINT_SPACING_S apart (grid.py says why)
    start, rows, _ = layout.blocks["durations"]
    longest = np.array([(c - 1) * MAX_POINT_SPACING_S for c in PHASE_LENGTH_POINTS[:rows]])
    high[start:start + rows] = np.minimum(high[start:start + rows], longest)
    return low, high


def _fitted(spline, target, nodal, shift: float, scale: float, derivatives, fractions) -> np.ndarray:
    """Nodal values of the periodic ``spline`` whose value and derivatives (per interval of ``spline``) best
    match, in least squares at the cycle ``fractions`` s, those of ``target`` (nodal values ``nodal``) at
    scale·s + shift."""
    a, b = [], []
    for r in derivatives:
        weight = spline.intervals ** -r  # d^r/ds^r in units of one interval of the fitted spline
        a.append(weight * evaluation_matrix(spline, fractions, r) * spline.intervals ** r)
        b.append(weight * evaluation_matrix(target, scale * fractions + shift, r) @ nodal
                 * (target.intervals * scale) ** r)
    return np.linalg.lstsq(np.vstack(a), np.vstack(b), rcond=None)[0]


def full_from_symmetric(nodes: int, x) -> np.ndarray:
    """The full model's χ of the gait a symmetric χ ``x`` describes, exactly: the legs' and muscles' nodal values
    as they are, the left's on its own nodes half a cycle on; hip and HAT's T/2-periodic spline (N_h intervals)
    as the spline of 2·N_h intervals over T it is, by its midpoint values; T_1…4 twice, L_l = L_r."""
    symmetric, full = DesignLayout.build(nodes, symmetric=True), DesignLayout.build(nodes, symmetric=False)
    blocks = symmetric.unpack(np.asarray(x, float))
    half = quartic(half_cycle_intervals(nodes - 1) + 1)
    trunk = full_trunk_spline(nodes)
    coefficients = np.vstack([half.bspline_of(blocks["trunk"])] * 2)  # the same knots, T/2 apart
    durations, steps = blocks["durations"].ravel(), blocks["steps"].ravel()
    return full.pack({"trunk": trunk.nodal_from_bspline @ coefficients,
                      "right_leg": blocks["right_leg"], "left_leg": blocks["right_leg"],
                      "right_stretch": blocks["right_stretch"], "left_stretch": blocks["right_stretch"],
                      "durations": np.tile(durations, 2), "steps": [steps[0], steps[0]]})


def symmetric_on_nodes(x, nodes_from: int, nodes: int) -> np.ndarray:
    """A symmetric χ ``x`` of ``nodes_from`` nodes on ``nodes`` nodes: each spline fitted in least squares to the
    old one's value and derivatives (as :func:`full_from_symmetric`); durations and step as they are."""
    old, new = DesignLayout.build(nodes_from, symmetric=True), DesignLayout.build(nodes, symmetric=True)
    blocks = old.unpack(np.asarray(x, float))
    if nodes == nodes_from:
        return new.pack(blocks)
    s = np.linspace(0.0, 1.0, 20 * max(nodes, nodes_from), endpoint=False)
    half = (quartic(half_cycle_intervals(nodes_from - 1) + 1), quartic(half_cycle_intervals(nodes - 1) + 1))
    fitted = {"trunk": _fitted(half[1], half[0], blocks["trunk"], 0.0, 1.0, (0, 1, 2), s),
              "right_leg": _fitted(quartic(nodes), quartic(nodes_from), blocks["right_leg"], 0.0, 1.0, (0, 1, 2), s),
              "right_stretch": _fitted(cubic(nodes), cubic(nodes_from), blocks["right_stretch"], 0.0, 1.0, (0, 1), s)}
    return new.pack({**fitted, "durations": blocks["durations"], "steps": blocks["steps"]})
