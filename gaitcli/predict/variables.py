"""The variables w of the predictive-gait NLP (Diss. 5.2.7–5.2.9, lifted): every block, its order, size and units.

w is the transcription's intermediate quantities made variables ("lifted") and tied together by equality
constraints (``constraints.py``): the problem is (5.24)'s over χ (``layout.py``), but each constraint touches
only a few variables. Blocks in order, each stored column-major (a column's values contiguous), every
variable O(1) as value / scale; N = nn − 1 spline intervals, N_h the half cycle's (odd), I the distinct
control instants (112 by default), I/2 the first half cycle's; in brackets the sizes at nn = 18 on the default
grid (:meth:`Variables.blocks` gives each block's place in w):

    block  full model       symmetric model   content                                          unit / scale
    C_t    N_t × 3 (54)     N_h × 3 (27)      the trunk's (hip x periodic part, hip z, HAT)      m, rad / 1
                                              quartic B-spline coefficients (symmetric:
                                              T/2-periodic; full: N_t = 2·N_h intervals over T)
    C_y    N × 6 (102)      N × 3 (51)        the legs' quartic B-spline coefficients (y4 … y6;  m, rad / 1
                                              full: then y7 … y9 on the left leg's knots, half
                                              a cycle on)
    C_s    N × 16 (272)     N × 8 (136)       the cubic tendon-stretch splines' B-spline         1 / 1
                                              coefficients ŝ (full: the right muscles', then
                                              the left's on the left leg's knots)
    T      8                4                 the phase durations T_1 … (symmetric: T_5…8 =      s / 0.1
                                              T_1…4)
    L      2                1                 the step lengths L_r, L_l (symmetric: L_l = L_r)   m / 1
    Q      I × 100 (11200)  I × 41 (4592)     per instant: y, ẏ, ÿ (9 each; symmetric: the right LIFTED_SCALE
                                              leg's 3), ŝ (16; 8), rhs (9; full model only),
                                              l_m, v_m, a (16 each; symmetric: 8)
    P      —                I/2 × 18 (1008)   the first half cycle's trunk y, ẏ, ÿ (3 each) and  LIFTED_SCALE
                                              rhs (9)
    Λ      Σ widths (436)   first half's (218)  the ground reactions λ_j of every stated control  N, N·m / 100
                                              point in grid order (the phase's reaction names)
    D      6 (prosthetic models only)         the device's coefficients in its law's order:       the law's SCALE
                                              (a_p, b_p, c0, a_n, b_n, d_prosth) of (5.58)–(5.59)
    w      12 074 (12 080 with D)  6 037 (6 043 with D)

A C block holds the coefficients c_j of periodic uniform B-splines (``splines.bspline_matrix``): the same
splines as (5.10)–(5.23), each segment's polynomial p_{k,0…d} a fixed linear function of d + 1 neighbouring
coefficients, so that the constraints touch few of them and no continuity rows are needed. χ's nodal values
(5.13) are p_{k,0} = ``spline.nodal_from_bspline`` · c. Units of Q:
y in m (y1, y2) or rad, ẏ per s, ÿ per s², ŝ dimensionless, rhs in N or N·m (5.1), l_m m, v_m m/s, a
dimensionless. Muscles removed with a prosthetic ankle (``WalkerMuscles.present``) keep their places, fixed
at zero by their bounds.

Symmetric model (5.3.1): the left leg is the right leg half a cycle later, hip and HAT repeat every half
cycle one half stride on: :attr:`Variables.values` gives every instant's full 9 coordinates and 16 muscles
either way, so that no later part of the problem distinguishes the two models.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np

from gaitcli.predict.grid import instant_times, periodic_steps
from gaitcli.predict.layout import DesignLayout, box_bounds, full_trunk_spline, half_cycle_intervals
from gaitcli.predict.pointwise import PointFunction
from gaitcli.predict.prosthesis import DEFAULT_LAW
from gaitcli.predict.splines import PeriodicSpline, local_values, quartic, window_coefficients

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
#: the lifted quantities of the full cycle's 9 coordinates (the rest are the 16 muscles')
COORDINATE_QUANTITIES = ("y", "yd", "ydd")


@dataclass
class SplineBlock:
    """One spline family of w: its B-spline coefficients ``variables`` (N × columns SX, the design variables),
    spline, the χ block it stands for; ``windows``: which segment list of the NLP places its windows ("cycle";
    "half" for the symmetric model's trunk, "trunk" for the full model's, "left" for the full model's left leg
    and muscles). ``coefficients`` are the segment coefficients p_{k,p} they make (5.10–5.12;
    ((d + 1)·N × columns), linear in ``variables``). Its values are those of the lifted quantities
    (``lifted_block``, from column ``lifted_offset``); ``drift``: its first column is hip x (y1).
    """

    name: str
    spline: PeriodicSpline
    variables: ca.SX
    design_block: str
    windows: str = "cycle"
    lifted_block: str = "Q"
    lifted_offset: int = 0
    drift: bool = False
    coefficients: ca.SX = field(init=False)

    def __post_init__(self) -> None:
        self.coefficients = ca.mtimes(ca.DM(self.spline.basis), self.variables)

    @property
    def muscles(self) -> bool:
        """Whether the family is tendon stretch (else coordinates)."""
        return self.design_block.endswith("stretch")


def spline_positions(layout: DesignLayout, fractions) -> dict:
    """Where each instant lies on each segment list, in intervals from the spline's start (numpy or CasADi
    ``fractions`` t/T of the I instants): "cycle" N·s; the symmetric model's "half" (first half cycle's
    instants) 2·N_h·s; the full model's "trunk" N_t·s and "left" N·(s − ½), one cycle on for the first
    half's instants (the left leg's splines start half a cycle after the right's)."""
    n, count = layout.nodes - 1, fractions.shape[0]
    if layout.symmetric:
        return {"cycle": fractions * n, "half": 2 * fractions[:count // 2] * half_spline(layout).intervals}
    first_half = np.arange(count) < count // 2
    wrap = ca.DM(first_half.astype(float)) if isinstance(fractions, (ca.SX, ca.MX, ca.DM)) else first_half
    return {"cycle": fractions * n, "trunk": fractions * full_trunk_spline(layout.nodes).intervals,
            "left": (fractions - 0.5 + wrap) * n}


def segment_counts(layout: DesignLayout) -> dict[str, int]:
    """The intervals of each segment list of ``layout`` (:func:`spline_positions`' keys)."""
    n = layout.nodes - 1
    if layout.symmetric:
        return {"cycle": n, "half": half_spline(layout).intervals}
    return {"cycle": n, "trunk": full_trunk_spline(layout.nodes).intervals, "left": n}


def half_spline(layout: DesignLayout) -> PeriodicSpline:
    """The trunk's T/2-periodic quartic of the symmetric model (N_h odd intervals)."""
    return quartic(half_cycle_intervals(layout.nodes - 1) + 1)


def mirror(row):
    """A 9-vector of generalized forces (or coordinates' rates) with the legs swapped."""
    return ca.vertcat(row[0:3], row[6:9], row[3:6])


class Variables:
    """The symbols of w (module docstring) for one transcriber's structure and χ layout, and the gait they
    describe over the whole cycle.

    ``durations`` (8,) s, ``steps_r``, ``steps_l`` m, ``period`` T, ``stride`` ΔS, ``times`` (I,) s and
    ``fractions`` t/T of the instants; ``values[name][i]`` the full model's column of quantity ``name`` ("y",
    "yd", "ydd": 9; "stretch", "l_m", "v_m", "a": 16) at instant i and ``generalized_forces[i]`` its rhs (9);
    ``reactions[j]`` λ (N) at stated control point j; ``coefficients`` the device's (its law's, zero without one);
    ``parameters`` p = (v, w1, w2); ``intervals`` the spline intervals of the segment lists that place the
    windows ("cycle": N; "half": N_h, symmetric model).

    What the symmetric model states once: ``dynamics_instants`` (the first half's), ``points`` (the control
    points of the first half cycle), ``muscle_columns`` (the right leg's 8) and ``energy_factor`` (its Et
    counts the right leg's muscles twice).
    """

    def __init__(self, transcriber, layout: DesignLayout):
        self.layout, self.symmetric, self.grid = layout, layout.symmetric, transcriber.grid
        self.n_i = self.grid.instants
        self.half = self.n_i // 2
        self._design_blocks(transcriber)
        self.period, self.stride = ca.sum1(self.durations), self.steps_r + self.steps_l
        self.times = instant_times(self.grid, self.durations)
        self.fractions = self.times / self.period
        #: p = (v, w1, w2): the speed (5.43) and the weights (5.29)
        self.parameters = ca.SX.sym("p", 3)
        muscles = transcriber.muscles
        self.all_present = muscles.present
        self.present = muscles.present[self.muscle_columns]
        self.kept = [k for k in range(8) if self.present[k]]  # of each leg's 8 muscles, those the model has
        self.columns = [k for k in range(self.muscle_columns.stop) if muscles.present[k]]  # of the modelled ones
        #: the prostheses' law (None without), their scaled coefficients D and the coefficients themselves
        self.device_law = type(muscles.prosthesis) if muscles.prosthetic else None
        law = self.device_law or DEFAULT_LAW
        self.device = ca.SX.sym("D", len(law.COEFFICIENTS)) if muscles.prosthetic else None
        self.coefficients = (self.device * ca.DM(law.SCALE) if muscles.prosthetic
                             else ca.DM.zeros(len(law.COEFFICIENTS)))
        self._lift()
        self._ground_reactions(transcriber.contact)
        self.values = {name: self._cycle_values(name) for name in ("y", "yd", "ydd", "stretch", "l_m", "v_m", "a")}
        self.generalized_forces = self._cycle_rhs()

    def _design_blocks(self, transcriber) -> None:
        """C, T, L and what the model states once (class docstring)."""
        sym, n = ca.SX.sym, self.layout.nodes - 1
        quartic_spline, cubic_spline = transcriber.quartic, transcriber.cubic
        if self.symmetric:
            half = half_spline(self.layout)
            self.intervals = segment_counts(self.layout)
            self.splines = [SplineBlock("trunk", half, sym("Ct", half.intervals, 3), "trunk", "half", "P",
                                        drift=True),
                            SplineBlock("leg", quartic_spline, sym("Cy", n, 3), "right_leg"),
                            SplineBlock("stretch", cubic_spline, sym("Cs", n, 8), "right_stretch")]
            self.spline_symbols = [b.variables for b in self.splines]
            self.durations_z, self.steps = sym("T", 4), sym("L", 1)
            self.durations = ca.vertcat(self.durations_z, self.durations_z) * DURATION_SCALE_S
            self.steps_r = self.steps_l = self.steps[0]
            self.lifted_blocks, self.points = SYMMETRIC_LIFTED, list(range(self.grid.points // 2))
            self.dynamics_instants, self.muscle_columns, self.energy_factor = range(self.half), slice(0, 8), 2.0
        else:
            trunk = full_trunk_spline(self.layout.nodes)
            self.intervals = segment_counts(self.layout)
            legs, stretch = sym("Cy", n, 6), sym("Cs", n, 16)
            self.splines = [SplineBlock("trunk", trunk, sym("Ct", trunk.intervals, 3), "trunk", "trunk", drift=True),
                            SplineBlock("leg", quartic_spline, legs[:, :3], "right_leg", lifted_offset=3),
                            SplineBlock("left_leg", quartic_spline, legs[:, 3:], "left_leg", "left", lifted_offset=6),
                            SplineBlock("stretch", cubic_spline, stretch[:, :8], "right_stretch"),
                            SplineBlock("left_stretch", cubic_spline, stretch[:, 8:], "left_stretch", "left",
                                        lifted_offset=8)]
            self.spline_symbols = [self.splines[0].variables, legs, stretch]
            self.durations_z, self.steps = sym("T", 8), sym("L", 2)
            self.durations = self.durations_z * DURATION_SCALE_S
            self.steps_r, self.steps_l = self.steps[0], self.steps[1]
            self.lifted_blocks, self.points = FULL_LIFTED, list(range(self.grid.points))
            self.dynamics_instants, self.muscle_columns, self.energy_factor = range(self.n_i), slice(0, 16), 1.0

    def family_columns(self, b: SplineBlock) -> tuple[list[int], list[int]]:
        """The columns of family ``b`` the problem models (a removed muscle's are not) and their columns in its
        lifted quantities."""
        if not b.muscles:
            columns = list(range(b.variables.shape[1]))
        else:
            columns = [k for k in range(b.variables.shape[1]) if self.all_present[b.lifted_offset + k]]
        return columns, [b.lifted_offset + k for k in columns]

    def position_offset(self, key: str, instant: int) -> float:
        """Instant ``instant``'s place on segment list ``key`` (:func:`spline_positions`) less its cycle
        fraction's multiple (N·s, or 2·N_h·s on the symmetric trunk's): a constant, −N/2 or N/2 on "left"."""
        if key != "left":
            return 0.0
        return self.intervals["left"] * ((1.0 if instant < self.half else 0.0) - 0.5)

    def _lift(self) -> None:
        """Q (and P): ``lifted[(block, quantity)]`` the (rows × columns) values, variables × scale."""
        self.lifted_symbols, self.lifted = [], {}
        for block, rows, quantities in self.lifted_blocks:
            q = ca.SX.sym(block, self.half if rows == "half" else self.n_i, sum(c for _, c in quantities))
            self.lifted_symbols.append(q)
            start = 0
            for name, cols in quantities:
                self.lifted[(block, name)] = q[:, start:start + cols] * LIFTED_SCALE[name]
                start += cols

    def _ground_reactions(self, contact) -> None:
        """Λ: ``phases`` (1–8) of every grid point, ``reactions[j]`` λ (N) of every stated point."""
        self.phases = [int(p) + 1 for p in self.grid.phase]
        widths = [len(contact.reaction_names[self.phases[j]]) for j in self.points]
        self.lam = ca.SX.sym("R", sum(widths))
        offsets = np.concatenate([[0], np.cumsum(widths)])
        self.reactions = {j: self.lam[offsets[k]:offsets[k + 1]] * REACTION_SCALE_N for k, j in enumerate(self.points)}

    def _cycle_values(self, name: str) -> list:
        """The full cycle's column of ``name`` at every instant (the symmetric model: left = right half a cycle
        later; hip and HAT the first half's, y1 one half stride on in the second half)."""
        q = self.lifted[("Q", name)]
        if not self.symmetric:
            return [q[i, :].T for i in range(self.n_i)]
        out = []
        for i in range(self.n_i):
            right, left = q[i, :].T, q[(i + self.half) % self.n_i, :].T
            if name in COORDINATE_QUANTITIES:
                trunk = self.lifted[("P", name)][i % self.half, :].T
                if name == "y" and i >= self.half:
                    trunk = trunk + ca.vertcat(self.stride / 2, 0, 0)  # y1(t + T/2) = y1(t) + ΔS/2
                out.append(ca.vertcat(trunk, right, left))
            else:
                out.append(ca.vertcat(right, left))
        return out

    def _cycle_rhs(self) -> list:
        """rhs (5.1) at every instant (the symmetric model: the first half's, mirrored in the second)."""
        if not self.symmetric:
            return [self.lifted[("Q", "rhs")][i, :].T for i in range(self.n_i)]
        rhs = self.lifted[("P", "rhs")]
        return [rhs[i % self.half, :].T if i < self.half else mirror(rhs[i % self.half, :].T) for i in range(self.n_i)]

    # ------------------------------------------------------------------------------------------- w as a whole
    @property
    def head(self) -> ca.SX:
        """w's spline part: C…, T, L."""
        return ca.vertcat(*[ca.vec(c) for c in self.spline_symbols], self.durations_z, self.steps)

    @property
    def w(self) -> ca.SX:
        """w = [C…, T, L, Q (, P), Λ (, D)]."""
        device = [self.device] if self.device is not None else []
        return ca.vertcat(self.head, *[ca.vec(q) for q in self.lifted_symbols], self.lam, *device)

    def blocks(self) -> dict[str, slice]:
        """Each block of w (module docstring) as a slice of w."""
        sizes = [(name, c.numel()) for name, c in zip(("C_t", "C_y", "C_s"), self.spline_symbols)]
        sizes += [("T", self.durations_z.numel()), ("L", self.steps.numel())]
        sizes += [(block, q.numel()) for (block, _, _), q in zip(self.lifted_blocks, self.lifted_symbols)]
        sizes += [("Λ", self.lam.numel())] + ([("D", self.device.numel())] if self.device is not None else [])
        out, start = {}, 0
        for name, size in sizes:
            out[name], start = slice(start, start + size), start + size
        return out

    def bounds(self, present: np.ndarray, step_m: float = 0.0,
               step_range_m: tuple[float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """lbw, ubw without D: the durations and steps as :func:`box_bounds` (the steps fixed at ``step_m``
        when > 0, else within ``step_range_m`` where given), the B-spline coefficients free
        (``constraints.nodal_rows`` bounds their nodal values); ŝ ≥ 0 (a taut or just slack tendon) and
        0 ≤ a ≤ 1; the ``present`` (16,) muscles' values free, the others' fixed at 0."""
        low, high = box_bounds(self.layout, present)
        blocks_low, blocks_high = self.layout.unpack(low), self.layout.unpack(high)
        if step_m > 0:
            blocks_low["steps"] = blocks_high["steps"] = np.full_like(blocks_low["steps"], step_m)
        elif step_range_m is not None:
            blocks_low["steps"] = np.full_like(blocks_low["steps"], step_range_m[0])
            blocks_high["steps"] = np.full_like(blocks_high["steps"], step_range_m[1])
        lbw, ubw = [], []
        for b in self.splines:  # the B-splines' coefficients free: their nodal values are bounded (``nodes`` rows)
            lo, hi = np.full(b.variables.shape, -np.inf), np.full(b.variables.shape, np.inf)
            if b.muscles:  # a removed muscle's spline is 0
                removed = ~self.all_present[b.lifted_offset:b.lifted_offset + b.variables.shape[1]]
                lo[:, removed], hi[:, removed] = 0.0, 0.0
            lbw.append(lo.ravel(order="F"))
            ubw.append(hi.ravel(order="F"))
        lbw += [blocks_low["durations"].ravel() / DURATION_SCALE_S, blocks_low["steps"].ravel()]
        ubw += [blocks_high["durations"].ravel() / DURATION_SCALE_S, blocks_high["steps"].ravel()]
        for (_, _, quantities), q in zip(self.lifted_blocks, self.lifted_symbols):
            lo, hi = [], []
            for name, cols in quantities:
                lo.append(np.full((q.size1(), cols), 0.0 if name in ("stretch", "a") else -np.inf))
                hi.append(np.full((q.size1(), cols), 1.0 if name == "a" else np.inf))
                if name in ("stretch", "l_m", "v_m", "a"):  # a removed muscle's values are fixed at 0
                    lo[-1][:, ~present[:cols]] = hi[-1][:, ~present[:cols]] = 0.0
            lbw.append(np.hstack(lo).ravel(order="F"))
            ubw.append(np.hstack(hi).ravel(order="F"))
        lbw.append(np.full(self.lam.size1(), -np.inf))
        ubw.append(np.full(self.lam.size1(), np.inf))
        return np.concatenate(lbw), np.concatenate(ubw)


def instant_steps(v: Variables) -> tuple[list, list]:
    """h1_i = t_i − t_{i−1} and h2_i = t_{i+1} − t_i of every instant (``grid.periodic_steps``), s: linear in the
    durations."""
    h1, h2 = periodic_steps(v.times, v.period)
    return [h1[i] for i in range(v.n_i)], [h2[i] for i in range(v.n_i)]


#: the lifted quantities of a coordinate family and of a tendon-stretch family, with their time derivatives
COORDINATE_SPLINE_QUANTITIES = (("y", 0), ("yd", 1), ("ydd", 2))
STRETCH_SPLINE_QUANTITIES = (("stretch", 0),)


def spline_functions(v: Variables, segments: dict, reach: int) -> list[PointFunction]:
    """The lifted y, ẏ, ÿ, ŝ are the splines' values at the instants (5.10–5.12), one point function per spline
    family: at instant i, (lifted − spline)/scale of its quantities (hip x with its drift ΔS/T; ŝ of the
    modelled muscles), the spline read from its window of segments ``segments[key][i]`` ± ``reach`` only
    (:func:`gaitcli.predict.splines.local_values`), of

        z = (the window's segment coefficients ((d + 1)·(2·reach + 1) × columns), the lifted values, t_i, T, ΔS,
             the window's first segment less the family's offset on its segment list)

    The symmetric model's trunk is T/2-periodic, read over the first half cycle; the full model's left leg and
    muscles on knots half a cycle after the right's (:func:`spline_positions`)."""
    out = []
    for b in v.splines:
        quantities = STRETCH_SPLINE_QUANTITIES if b.muscles else COORDINATE_SPLINE_QUANTITIES
        columns, lifted_columns = v.family_columns(b)
        half = b.windows == "half"
        instants = range(v.half) if half else range(v.n_i)
        function = _spline_function(b, len(columns), quantities, b.drift, 2.0 if half else 1.0, reach)
        inputs = []
        for i in instants:
            first = int(segments[b.windows][i]) - reach
            window = window_coefficients(b.spline, b.coefficients[:, columns], (first, first + 2 * reach))
            lifted = [v.lifted[(b.lifted_block, q)][i, lifted_columns].T for q, _ in quantities]
            inputs.append(ca.vertcat(ca.vec(window), *lifted, v.times[i], v.period, v.stride,
                                     first - v.position_offset(b.windows, i)))
        out.append(PointFunction(f"splines_{b.name}", function, ca.horzcat(*inputs)))
    return out


def _spline_function(b: SplineBlock, columns: int, quantities: tuple, drifts: bool, cycles: float,
                     reach: int) -> ca.Function:
    """:func:`spline_functions`' function of one family (``cycles`` of the spline per gait cycle)."""
    size = (b.spline.degree + 1) * (2 * reach + 1) * columns
    z = ca.SX.sym("z", size + len(quantities) * columns + 4)
    coefficients = ca.reshape(z[:size], size // columns, columns)
    t, period, stride, first = z[-4], z[-3], z[-2], z[-1]
    position = cycles * t / period * b.spline.intervals - first
    values = local_values(b.spline, coefficients, period / cycles, position, [r for _, r in quantities])
    if drifts:  # y1 = periodic part + (ΔS/T)·t (splines.py, "Hip x")
        values[0][0] += stride / period * t
        values[1][0] += stride / period
    rows = []
    for k, ((name, _), value) in enumerate(zip(quantities, values)):
        lifted = z[size + k * columns:size + (k + 1) * columns]
        rows.append((lifted - value.T) / LIFTED_SCALE[name])
    return ca.Function(f"splines_{b.name}", [z], [ca.vertcat(*rows)], ["z"], ["splines"])
