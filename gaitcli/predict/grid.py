"""Control points of the predictive gait NLP (5.2.5, 5.2.10) and the unequal-step time derivative on them (5.2.6).

Control points (5.2.5, 5.2.10; docs/prediction.md, "Control points")
    Independent of the spline nodes and uniform within each of the 8 phases: phase ph of
    duration T_ph (s) has n_c,ph points at t = t0_ph + T_ph·i/(n_c,ph − 1), i = 0 … n_c,ph − 1,
    t0_ph = Σ_{q<ph} T_q, time 0 at the cycle's first instant (HSr). The default counts
    9, 10, 21, 20, 9, 10, 21, 20 include both end points, so a transition instant is an
    evaluation point of both adjacent phases: Σn_c,ph = 120 points, Σ(n_c,ph − 1) = 112 distinct
    instants per cycle. The contact-dependent quantities (λ, joint moments, e_m, c_ph,
    clearance, friction) are evaluated at all 120 points, a transition once with each adjacent
    phase's constraint set; the continuous ones (muscle forces, activations) at the 112
    instants (:attr:`ControlGrid.instant`). The last point of phase 8 is the instant t = T,
    which is instant 0 of the next cycle.

    Deviation: 5.2.10 has 5 points in phases 1 and 5 (HS→TC) and 4 in phases 4 and 8 (HOr→HSl).
    With the durations free the optimizer lengthened the sparsest phase and hid the push-off's
    muscle work between its points; no phase longer than :data:`MAX_POINT_SPACING_S` per interval
    of :data:`PHASE_LENGTH_POINTS` (``layout.box_bounds``) keeps it short, and 9 points in the heel
    rocker and 20 from heel off keep the excitations within [−0.05, 1.05] between the points, where
    the tibialis anterior and rectus femoris at heel strike and the gastrocnemius's push-off change
    faster than 5 and 12 points follow (docs/decisions.md, "Control points").

    Every point's time is linear in the durations: t_j = W_j · [T_1 … T_8] with the constant
    matrix W = :attr:`ControlGrid.time_weights`, so the times are numpy or CasADi expressions
    alike (:func:`point_times`, :func:`instant_times`).

Unequal-step derivative (5.2.6)
    At instant j with h1 = t_j − t_{j−1}, h2 = t_{j+1} − t_j (second order, exact on quadratics,
    the central difference when h1 = h2):

        ẋ_j ≈ −h2/(h1(h1 + h2))·x_{j−1} + (h2 − h1)/(h1 h2)·x_j + h1/(h2(h1 + h2))·x_{j+1},

    periodic over the distinct instants of one cycle (t_{−1} = t_{I−1} − T, t_I = t_0 + T):
    :func:`periodic_derivative`. Times in s, ẋ in the unit of x per s.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.core.validate import integer
from gaitcli.errors import InputError
from gaitcli.predict.splines import casadi_column, is_casadi

#: phases of the cycle (HSr→TCr, TCr→TOl, TOl→HOr, HOr→HSl and the mirrored four; Fig. 5.3)
PHASES = 8
#: n_c,ph per phase, both end points included (5.2.10; phases 1, 4, 5 and 8 denser: module docstring)
DEFAULT_CONTROL_POINTS = (9, 10, 21, 20, 9, 10, 21, 20)
#: the time between control points, s, that bounds each phase's duration: ≤ (n_ph − 1) × this with n_ph of
#: :data:`PHASE_LENGTH_POINTS` (0.16, 0.36, 0.80, 0.28 s)
MAX_POINT_SPACING_S = 0.04
PHASE_LENGTH_POINTS = (5, 10, 21, 8, 5, 10, 21, 8)


@dataclass(frozen=True)
class ControlGrid:
    """The structure of the control points (constant; the times follow from the durations).

    Per evaluation point j (P = Σn_c,ph): ``phase`` (0 … 7), ``position`` i/(n_c,ph − 1) within
    its phase, ``instant`` (index of the distinct instant, 0 … I − 1) and ``time_weights``
    (P, 8) with t_j = time_weights[j] · T_ph.
    """

    counts: tuple[int, ...]
    phase: np.ndarray
    position: np.ndarray
    instant: np.ndarray
    time_weights: np.ndarray

    @property
    def points(self) -> int:
        """P = Σn_c,ph evaluation points (120 by default)."""
        return len(self.phase)

    @property
    def instants(self) -> int:
        """I = Σ(n_c,ph − 1) distinct instants per cycle (112 by default)."""
        return sum(self.counts) - len(self.counts)

    @property
    def instant_points(self) -> np.ndarray:
        """Index of the point that opens each instant (its time lies in [0, T))."""
        return np.unique(self.instant, return_index=True)[1]

    @property
    def wraps(self) -> np.ndarray:
        """Whether a point closes the cycle (t = T: instant 0 of the next cycle, hip x one stride on)."""
        return np.all(self.time_weights == 1.0, axis=1)


def control_grid(counts=DEFAULT_CONTROL_POINTS) -> ControlGrid:
    """The control points of ``counts`` (n_c,ph for the 8 phases, each ≥ 2, both end points included)."""
    counts = tuple(counts)
    if len(counts) != PHASES:
        raise InputError(None, "control_points", f"got {len(counts)} counts (expected {PHASES}, one per phase)")
    for n in counts:
        integer(n, where="control_points", low=2)
    offsets = np.concatenate([[0], np.cumsum(np.array(counts) - 1)])
    total = int(offsets[-1])
    phase, position, instant = [], [], []
    for ph, n in enumerate(counts):
        i = np.arange(n)
        phase.append(np.full(n, ph))
        position.append(i / (n - 1))
        instant.append((offsets[ph] + i) % total)
    phase, position = np.concatenate(phase), np.concatenate(position)
    weights = (np.arange(PHASES)[None, :] < phase[:, None]).astype(float)
    weights[np.arange(len(phase)), phase] = position
    return ControlGrid(counts, phase, position, np.concatenate(instant), weights)


def _linear_in_durations(weights: np.ndarray, durations):
    if is_casadi(durations):
        return ca.mtimes(ca.DM(weights), casadi_column(durations))
    return weights @ np.asarray(durations, float)


def cycle_period(durations):
    """T = ΣT_ph (s): a float, or a CasADi scalar for symbolic durations."""
    if is_casadi(durations):
        return ca.sum1(casadi_column(durations))
    return float(np.sum(durations))


def point_times(grid: ControlGrid, durations):
    """Times (s, from the cycle's start) of all P evaluation points; (P,) or a (P × 1) CasADi expression."""
    return _linear_in_durations(grid.time_weights, durations)


def instant_times(grid: ControlGrid, durations):
    """Times (s) of the I distinct instants, increasing in [0, T); (I,) or an (I × 1) CasADi expression."""
    return _linear_in_durations(grid.time_weights[grid.instant_points], durations)


def _neighbours(n: int) -> tuple[list[int], list[int]]:
    integer(n, where="instants", low=3)
    return [n - 1] + list(range(n - 1)), list(range(1, n)) + [0]


def periodic_steps(times, period):
    """(h1, h2): each instant's step back to the one before and on to the one after, s, at ``times`` (one cycle
    of ``period``, wrapped: t_{−1} = t_{I−1} − T, t_I = t_0 + T); columns, numpy or CasADi alike."""
    symbolic = is_casadi(times, period)
    t = casadi_column(times) if symbolic else np.asarray(times, float).ravel()
    n = t.shape[0]
    before, after = _neighbours(n)
    first = np.eye(n)[0]
    last = np.eye(n)[-1]
    if symbolic:
        first, last = ca.DM(first), ca.DM(last)
    return t - t[before] + period * first, t[after] - t + period * last


def unequal_step_weights(times, period):
    """Weights (a, b, c) of ẋ_j ≈ a_j x_{j−1} + b_j x_j + c_j x_{j+1} at ``times``
    (one cycle of ``period``, wrapped)."""
    return step_weights(*periodic_steps(times, period))


def step_weights(h1, h2):
    """(a, b, c) of ẋ ≈ a·x_{−1} + b·x_0 + c·x_{+1} with steps h1 before and h2 after (module docstring)."""
    return -h2 / (h1 * (h1 + h2)), (h2 - h1) / (h1 * h2), h1 / (h2 * (h1 + h2))


def step_derivative(before, now, after, h1, h2):
    """ẋ at one instant from x one step ``h1`` before, now and one step ``h2`` after (module docstring)."""
    a, b, c = step_weights(h1, h2)
    return a * before + b * now + c * after


def periodic_derivative(values, times, period):
    """ẋ at the periodic ``times`` (I distinct instants, s) of ``values`` (I,) or (I, n) (5.2.6).

    With a grid: ``periodic_derivative(x, instant_times(grid, T_ph), cycle_period(T_ph))``. Numpy in,
    numpy out; any CasADi input gives an (I × n) CasADi expression.
    """
    weights = unequal_step_weights(times, period)
    before, after = _neighbours(weights[0].shape[0])
    if not is_casadi(values, *weights):
        x = np.asarray(values, float)
        shape = (-1,) + (1,) * (x.ndim - 1)
        a, b, c = (np.reshape(w, shape) for w in weights)
        with np.errstate(invalid="ignore"):  # an inf (e.g. a force no muscle state makes): NaN at it and beside it
            return a * x[before] + b * x + c * x[after]
    x = values if is_casadi(values) else ca.DM(np.asarray(values, float))
    a, b, c = (ca.repmat(casadi_column(w), 1, x.shape[1]) for w in weights)
    return a * x[before, :] + b * x + c * x[after, :]
