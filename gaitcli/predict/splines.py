"""Periodic splines of the predictive gait NLP (5.2.4): the coordinates and the muscle forces over one cycle.

What
    Every coordinate y_n (quartic, C3, 5.10–5.21) and every muscle force f^m_i (cubic, C2,
    5.22–5.23) is a periodic piecewise polynomial on nn uniformly spaced nodes t_1 … t_nn over
    one gait cycle of period T = ΣT_ph; N = nn − 1 intervals, Δt = T/N. Segment k (0-based,
    t_k ≤ t ≤ t_k + Δt) is written in the normalised variable τ = (t − t_k)/Δt ∈ [0, 1]:

        φ_k(τ) = p_{k,0} + p_{k,1} τ + … + p_{k,d} τ^d                       (5.10–5.12, d = 4 or 3)

    with φ_k(0) = y_k (5.13), continuity of derivatives 0 … d−1 at every interior node
    (5.14–5.17) and at the wrap t_nn ≡ t_1 (5.18–5.21); the design variables are the N nodal
    values y_1 … y_N (the value at t_nn is y_1). In τ the system does not contain T, so the
    linear map from the nodal values to the (d + 1)·N coefficients is one numpy matrix per
    (degree, N), computed once (:func:`quartic`, :func:`cubic`, cached); time derivatives are
    d^r/dt^r = Δt^−r · d^r/dτ^r.

Singularity (5.2.4; docs/prediction.md, "Spline parity")
    The periodic quartic system is singular exactly when N is even ("an odd number of
    nodes"): :func:`quartic` rejects an odd nn with a one-line InputError naming ``nodes``.
    The same holds for a half-period quartic (symmetry): its node count must be even too.
    The periodic cubic system is regular for every N.

Hip x (5.43; docs/prediction.md, "Hip x and the speed")
    y1(t) = periodic(t) + v·t with v = ΔS/T (ΔS = L_r + L_l), so y1(t + T) = y1(t) + ΔS
    (:func:`hip_x`); t is the time since t_1 and is not wrapped in the drift term.

Units
    Times and T in s; nodal values in the signal's unit (rad, m or N); the r-th derivative in
    that unit per s^r; ΔS in m.

Variable layout
    Nodal values of one signal are a length-N vector (y_1 … y_N); n signals on the same nodes
    are an (N, n) matrix, one column per signal, and every function here returns one column per
    signal. The design vector (5.24) is χ = [y_{1,1…N}, …, y_{f,1…N}, f^m_{1,1…N}, …,
    f^m_{m,1…N}, T_1 … T_8, L_r, L_l] (signal-major), so ``casadi.reshape(χ[:f*N], N, f)``
    (column-major) is the coordinates' matrix; size (f + m)(nn − 1) + 10
    (:func:`design_vector_size`; 435 at f = 9, m = 16, nn = 18). The code's χ carries each muscle's
    tendon stretch ŝ in place of its force f^m (``layout.py``; docs/prediction.md).

Symbolic values, period and times (CasADi)
    Nodal values and T may be numpy arrays or CasADi SX/MX; the result is numpy only when all
    inputs are. Times (or cycle fractions) may be numeric or CasADi expressions (control-point
    times are linear in the phase durations T_ph, see ``grid.py``). The segment of a time is
    k = min(⌊N·frac(t/T)⌋, N − 1) (frac(s) = s − ⌊s⌋ wraps times beyond one period):

    - numeric fractions: k and τ are computed in numpy and the evaluation row is a constant
      matrix (:func:`evaluation_matrix`), so the expression is linear in the nodal values;
    - symbolic fractions: k is computed in the expression graph (``casadi.floor``) and the
      row is the one-hot combination Σ_κ [k = κ]·row_κ(τ) of the N segments' rows (O(N) per
      time). ⌊·⌋ has zero derivative, so the gradient is that of the active segment; because
      adjacent segments agree in derivatives 0 … d−1 at a node, derivative r of the spline and
      its gradient w.r.t. the times, T and the nodal values stay continuous when a time
      crosses a node as long as r ≤ d − 2 (quartic: value, ẏ, ÿ; cubic: value, ẏ).

    This was chosen over a caller-supplied fixed segment (wrong once a control point moves
    across a node during the iterations) and over a smooth blend of segments (not exact).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from math import factorial

import casadi as ca
import numpy as np

from gaitcli.core.validate import integer, one_of
from gaitcli.errors import InputError

#: the phases whose durations T_ph are design variables, plus the step lengths L_r, L_l (5.24)
PHASE_AND_STEP_VARIABLES = 8 + 2


@dataclass(frozen=True)
class PeriodicSpline:
    """The linear map of a periodic spline: coefficients p = matrix · y (normalised variable τ).

    ``matrix`` is ((degree + 1)·N, N), row (d + 1)·k + p giving p_{k,p} of segment k; read-only. The design values
    y are the spline's values at τ = ``sample_offset`` of every interval: 0, the nodal values (5.13); ½, the
    values at the intervals' midpoints (:func:`quartic_midpoints`).
    """

    degree: int
    intervals: int
    matrix: np.ndarray
    sample_offset: float = 0.0

    @property
    def nodes(self) -> int:
        """nn = N + 1 (the last node repeats the first)."""
        return self.intervals + 1

    @property
    def blocks(self) -> np.ndarray:
        """The matrix as (N, degree + 1, N): blocks[k, p] maps the nodal values to p_{k,p}."""
        return self.matrix.reshape(self.intervals, self.degree + 1, self.intervals)

    @property
    def basis(self) -> np.ndarray:
        """((degree + 1)·N, N): the segment coefficients p_{k,p} (rows as :attr:`matrix`'s) of the spline whose
        periodic uniform B-spline coefficients are c (:func:`bspline_matrix`); banded: segment k reads
        c_{k−d+s} … c_{k+s} (indices modulo N, s = ⌊(d + 1)/2⌋)."""
        return bspline_matrix(self.degree, self.intervals)

    @property
    def nodal_from_bspline(self) -> np.ndarray:
        """(N, N): the design values of B-spline coefficients c (circulant): the nodal values y_k = p_{k,0}
        (5.13), or the values Σ_p p_{k,p}·τ^p at τ = :attr:`sample_offset`."""
        return samples_from_bspline(self.degree, self.intervals, self.sample_offset)

    def bspline_of(self, values) -> np.ndarray:
        """The B-spline coefficients c (N,) or (N, n) of the spline with nodal values ``values``: the inverse
        of :attr:`nodal_from_bspline` (regular wherever :attr:`matrix` exists)."""
        return np.linalg.solve(self.nodal_from_bspline, np.asarray(values, float))


def _rate(p: int, r: int) -> float:
    """d^r/dτ^r τ^p = rate · τ^(p − r): p!/(p − r)! (0 for p < r)."""
    return factorial(p) / factorial(p - r) if p >= r else 0.0


@cache
def _periodic_matrix(degree: int, intervals: int) -> np.ndarray:
    """Solve (5.13)–(5.21) (quartic) or (5.22)–(5.23) (cubic) for the coefficients as a matrix of the
    nodal values."""
    n, width = intervals, degree + 1
    a = np.zeros((width * n, width * n))
    b = np.zeros((width * n, n))
    for k in range(n):
        a[k, width * k] = 1.0  # φ_k(0) = y_k
        b[k, k] = 1.0
        nxt = (k + 1) % n  # the wrap: segment N − 1 joins segment 0
        for r in range(degree):  # φ_k^(r)(1) = φ_{k+1}^(r)(0)
            row = n + degree * k + r
            a[row, width * k:width * (k + 1)] = [_rate(p, r) for p in range(width)]
            a[row, width * nxt + r] -= factorial(r)
    matrix = np.linalg.solve(a, b)
    matrix.setflags(write=False)
    return matrix


@cache
def bspline_matrix(degree: int, intervals: int) -> np.ndarray:
    """((d + 1)·N, N): segment coefficients p_{k,p} (τ-powers, rows as :attr:`PeriodicSpline.matrix`'s) of
    Σ_j c_j·B(x − j + s), x = N·t/T, B the cardinal B-spline of degree d (support [0, d + 1], knots at the
    integers), s = ⌊(d + 1)/2⌋ so that c_j's basis function peaks at or just after node j.

    The periodic B-splines of degree d on the N uniform intervals span exactly the periodic C^{d−1}
    piecewise polynomials of (5.14)–(5.23): the same splines, with coefficients that act locally (segment k
    reads d + 1 of them) where a nodal value acts on every segment. Each piece of B is read off exactly by
    interpolating d + 1 of its values (scipy's B-spline evaluation) with a polynomial in τ."""
    from scipy.interpolate import BSpline

    width, shift = degree + 1, (degree + 1) // 2
    cardinal = BSpline.basis_element(np.arange(degree + 2, dtype=float), extrapolate=False)
    tau = np.linspace(0.0, 1.0, width)
    vandermonde = tau[:, None] ** np.arange(width)
    pieces = [np.linalg.solve(vandermonde, np.nan_to_num(cardinal(i + tau))) for i in range(width)]
    out = np.zeros((width * intervals, intervals))
    for k in range(intervals):
        for i, piece in enumerate(pieces):  # B(k + τ − j + s) on piece i: j = k + s − i
            out[width * k:width * (k + 1), (k + shift - i) % intervals] += piece
    out.setflags(write=False)
    return out


@cache
def samples_from_bspline(degree: int, intervals: int, offset: float) -> np.ndarray:
    """(N, N): the values at τ = ``offset`` of every interval of the periodic B-spline with coefficients c."""
    basis = bspline_matrix(degree, intervals)
    out = sum(offset ** p * basis[p::degree + 1] for p in range(degree + 1))
    out.setflags(write=False)
    return out


@cache
def _midpoint_matrix(intervals: int) -> np.ndarray:
    matrix = bspline_matrix(4, intervals) @ np.linalg.inv(samples_from_bspline(4, intervals, 0.5))
    matrix.setflags(write=False)
    return matrix


def quartic_midpoints(intervals: int) -> PeriodicSpline:
    """The periodic C3 quartic spline on ``intervals`` uniform intervals designed by its values at the intervals'
    midpoints: regular for every count, even ones too (where the nodal values of :func:`quartic` are not; the
    full model's hip and HAT, ``layout.py``)."""
    integer(intervals, where="intervals", low=3)
    return PeriodicSpline(4, intervals, _midpoint_matrix(intervals), 0.5)


def quartic(nodes: int) -> PeriodicSpline:
    """The periodic C3 quartic spline on ``nodes`` = nn nodes (5.10–5.21); nn must be even (N = nn − 1 odd)."""
    integer(nodes, where="nodes", low=4)
    if nodes % 2:
        raise InputError(None, "nodes", f"got {nodes} (expected an even number of nodes: with an odd number "
                                        "the periodic quartic spline is singular, 5.2.4)")
    return PeriodicSpline(4, nodes - 1, _periodic_matrix(4, nodes - 1))


def cubic(nodes: int) -> PeriodicSpline:
    """The periodic C2 cubic spline on ``nodes`` = nn nodes (5.22–5.23); regular for every nn ≥ 3."""
    integer(nodes, where="nodes", low=3)
    return PeriodicSpline(3, nodes - 1, _periodic_matrix(3, nodes - 1))


def design_vector_size(nodes: int, coordinates: int = 9, muscles: int = 16, extra: int = 0) -> int:
    """Length of χ (5.24): (f + m)(nn − 1) + 10, plus ``extra`` (e.g. 6 prosthesis parameters)."""
    return (coordinates + muscles) * (nodes - 1) + PHASE_AND_STEP_VARIABLES + extra


def is_casadi(*xs) -> bool:
    """Whether any of ``xs`` is a CasADi matrix (SX, MX or DM) or a list/tuple holding one."""
    return any(isinstance(x, (ca.SX, ca.MX, ca.DM))
               or (isinstance(x, (list, tuple)) and is_casadi(*x)) for x in xs)


def casadi_column(x):
    """``x`` as a CasADi column: CasADi matrices as they are, lists of scalars stacked, numbers/arrays as DM."""
    if isinstance(x, (ca.SX, ca.MX, ca.DM)):
        return x
    if isinstance(x, (list, tuple)) and is_casadi(*x):
        return ca.vertcat(*x)
    return ca.DM(np.asarray(x, float).reshape(-1, 1))


def _terms(spline: PeriodicSpline, derivative: int) -> list[tuple[int, float]]:
    """(p, p!/(p − r)!) of the powers τ^p whose r-th τ-derivative is not zero."""
    one_of(derivative, tuple(range(spline.degree)), where="derivative")
    return [(p, _rate(p, derivative)) for p in range(derivative, spline.degree + 1)]


def _segments(spline: PeriodicSpline, fractions, lib=np):
    """Segment k = min(⌊N·frac(s)⌋, N − 1) and τ = N·frac(s) − k of cycle fractions s (``lib``: np or ca)."""
    x = (fractions - lib.floor(fractions)) * spline.intervals
    k = (np.minimum if lib is np else ca.fmin)(lib.floor(x), spline.intervals - 1)
    return k, x - k


def evaluation_matrix(spline: PeriodicSpline, fractions, derivative: int = 0) -> np.ndarray:
    """E (n_t × N) with d^r/dτ^r of the spline at the numeric cycle ``fractions`` (t/T, any real) = E · y.

    Constant, so that the expression is linear in the nodal values; multiply by Δt^−r for time derivatives.
    """
    k, tau = _segments(spline, np.asarray(fractions, float).ravel())
    k, tau = k.astype(int), tau[:, None]
    return sum(rate * tau ** (p - derivative) * spline.blocks[k, p] for p, rate in _terms(spline, derivative))


def evaluate_fractions(spline: PeriodicSpline, values, period, fractions, derivative: int = 0):
    """d^r y/dt^r at the cycle fractions s = t/T: values (N,) or (N, n) nodal values, ``period`` T in s.

    Returns (n_t,) or (n_t, n) for numpy inputs, an (n_t × n) CasADi expression otherwise. Symbolic
    fractions select each time's segment by the one-hot [k = κ] of its coefficients (module docstring).
    """
    scale = (period / spline.intervals) ** derivative
    if not is_casadi(fractions):
        e = evaluation_matrix(spline, fractions, derivative)
        if not is_casadi(values, period):
            return e @ np.asarray(values, float) / scale
        return ca.mtimes(ca.DM(e), values if is_casadi(values) else ca.DM(np.asarray(values, float))) / scale
    y = values if is_casadi(values) else ca.DM(np.asarray(values, float))
    coefficients = ca.mtimes(ca.DM(spline.matrix), y)  # row (d + 1)·κ + p: p_{κ,p} of every signal
    k, tau = _segments(spline, casadi_column(fractions), ca)
    onehot = ca.horzcat(*[k == kappa for kappa in range(spline.intervals)])  # (n_t × N)
    out = 0
    for p, rate in _terms(spline, derivative):
        selected = ca.mtimes(onehot, coefficients[p::spline.degree + 1, :])  # (n_t × n): p_{k(t),p}
        power = rate if p == derivative else ca.repmat(rate * tau ** (p - derivative), 1, y.shape[1])
        out += power * selected
    return out / scale


def evaluate(spline: PeriodicSpline, values, period, times, derivative: int = 0):
    """d^r y/dt^r at ``times`` in s since t_1 (any real: wrapped by the period); see :func:`evaluate_fractions`."""
    if is_casadi(times, period):
        return evaluate_fractions(spline, values, period, casadi_column(times) / period, derivative)
    return evaluate_fractions(spline, values, period, np.asarray(times, float) / period, derivative)


def hip_x(spline: PeriodicSpline, values, period, stride_m, times, derivative: int = 0):
    """Hip x (y1): the periodic spline of ``values`` (N,) plus the drift v·t, v = ΔS/T
    (``stride_m``: ΔS = L_r + L_l).

    y1(t + T) = y1(t) + ΔS. Numpy inputs give (n_t,); any CasADi input an (n_t × 1) expression.
    """
    periodic = evaluate(spline, values, period, times, derivative)
    if derivative > 1:
        return periodic
    speed = stride_m / period
    if not is_casadi(periodic):
        t = np.asarray(times, float).ravel()
        return np.ravel(periodic) + (speed * t if derivative == 0 else speed * np.ones_like(t))
    t = casadi_column(times)
    return periodic + (speed * t if derivative == 0 else speed * ca.DM.ones(t.size1(), 1))


@cache
def _continuity_matrix(degree: int, intervals: int) -> np.ndarray:
    width = degree + 1
    out = np.zeros((degree * intervals, width * intervals))
    for k in range(intervals):
        nxt = (k + 1) % intervals
        for r in range(degree):
            out[degree * k + r, width * k:width * (k + 1)] = [_rate(p, r) for p in range(width)]
            out[degree * k + r, width * nxt + r] -= factorial(r)
    out.setflags(write=False)
    return out


def continuity_matrix(spline: PeriodicSpline) -> np.ndarray:
    """K (N·d × (d + 1)·N): K·p = 0 are the continuity conditions (5.14)–(5.21) (cubic: 5.22–5.23) of the
    segment coefficients p (rows as :attr:`PeriodicSpline.matrix`'s), φ_k^(r)(1) = φ_{k+1}^(r)(0) for
    r = 0 … d − 1 with the wrap. With p_{k,0} = y_k (5.13) they define the spline: K·matrix = 0."""
    return _continuity_matrix(spline.degree, spline.intervals)


def evaluate_window(spline: PeriodicSpline, coefficients, period, fraction: float | object, window: tuple[int, int],
                    derivative: int = 0):
    """d^r y/dt^r at one cycle fraction s = t/T ∈ [0, 1) from segment coefficients (rows as
    :attr:`PeriodicSpline.matrix`'s, one column per signal), looking only at the segments
    ``window`` = (first, last) (indices taken modulo N): :func:`window_values` for one derivative."""
    return window_values(spline, coefficients, period, fraction, window, (derivative,))[0]


def window_values(spline: PeriodicSpline, coefficients, period, fraction: float | object, window: tuple[int, int],
                  derivatives=(0,)) -> list:
    """[d^r y/dt^r for r in ``derivatives``] at one cycle fraction s from the segments ``window`` only.

    The segment is ⌊N·s⌋ clamped into the window (beyond it the nearest window segment's polynomial is
    extrapolated), so the expression depends on the window's coefficients alone: what makes the NLP's
    Jacobian and Hessian sparse. A caller checks that ⌊N·s⌋ lies in the window at the solution
    (:func:`segment_of`); then the value is the spline's (:func:`local_values`).
    """
    first, last = window
    return local_values(spline, window_coefficients(spline, coefficients, window), period,
                        fraction * spline.intervals - first, derivatives)


def window_coefficients(spline: PeriodicSpline, coefficients, window: tuple[int, int]):
    """The rows of the segment coefficients ``coefficients`` ((d + 1)·N × columns) of the segments ``window`` =
    (first, last), indices modulo N, in order: ((d + 1)·(last − first + 1) × columns)."""
    n, width = spline.intervals, spline.degree + 1
    first, last = window
    return ca.vertcat(*[coefficients[width * (kappa % n):width * (kappa % n + 1), :]
                        for kappa in range(first, last + 1)])


def local_values(spline: PeriodicSpline, coefficients, period, position, derivatives=(0,)) -> list:
    """[d^r y/dt^r for r in ``derivatives``] (each 1 × columns) at ``position`` segments from the start of a
    window whose segment coefficients are ``coefficients`` ((d + 1)·K × columns, :func:`window_coefficients`).

    The segment is ⌊position⌋ clamped into the window's K, τ = position − segment; its coefficients are
    selected once and its polynomial differentiated for every r (Σ_κ [k = κ]·Σ_p c_κp·τ^p = Σ_p (Σ_κ [k =
    κ]·c_κp)·τ^p: a third of the expression of one polynomial per window segment and derivative).
    """
    n, width = spline.intervals, spline.degree + 1
    count = coefficients.shape[0] // width
    k = ca.fmin(ca.fmax(ca.floor(position), 0), count - 1)
    tau = position - k
    if count > 1:
        rows = sum((k == kappa) * coefficients[width * kappa:width * (kappa + 1), :] for kappa in range(count))
    else:
        rows = coefficients[:width, :]
    return [sum(rate * tau ** (p - r) * rows[p, :] for p, rate in _terms(spline, r)) / (period / n) ** r
            for r in derivatives]


def segment_of(spline: PeriodicSpline, fractions) -> np.ndarray:
    """⌊N·s⌋ of numeric cycle fractions s ∈ [0, 1): the segment each one lies in."""
    return np.minimum(np.floor(np.asarray(fractions, float) * spline.intervals), spline.intervals - 1).astype(int)
