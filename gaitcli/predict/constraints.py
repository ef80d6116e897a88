"""The inequality constraints of the predictive gait per phase (Diss. 5.2.9, with the notes' corrections).

Which contact points each group applies to follows from the phase table
(:data:`gaitcli.predict.contact.PHASE_TABLE`), not from the printed lists, two of
which are typos (CHAPTER5_NOTES §3 item 8):

- clearance (5.33–5.36): every heel A and MTP B *not* in contact stays at or above
  ``h_min`` (default 0 m; "r_z > 0" as a closed bound, §3 item 9);
- unilateral contact (5.37–5.40): the vertical reaction f_z ≥ 0 at every point in contact;
- friction (5.41–5.42): |f_x| ≤ μ·f_z per foot in contact, as the two smooth linear
  inequalities f_x − μ f_z ≤ 0 and −f_x − μ f_z ≤ 0; μ = 0.8 by default (the
  dissertation gives none; our choice, configurable);
- gait shape (5.45–5.48): in its swing (phases 7–8 right, 3–4 left) a knee flexes at least
  θ_knee = 60°; in late stance (phases 4–6 right, 1, 2, 8 left) a thigh extends at least
  θ_hip = 5° — the absolute thigh angle y4/y7, as the equations say (§3 item 2). The
  non-smooth max over control points becomes the log-sum-exp surrogate
  LSE_β(x) = max x + log Σ exp(β(x − max x))/β, an upper bound within ln(n)/β of the max
  (§3 item 10; β = 500 rad⁻¹: ≤ 0.50° for 80 points); the true max is reported.

All functions take numpy arrays or CasADi expressions.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.core.validate import number
from gaitcli.predict.contact import PHASE_TABLE, PHASES
from gaitcli.predict.splines import is_casadi

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
    """LSE_β(values): a smooth upper bound of max(values), within ln(n)/β of it (§3 item 10)."""
    if is_casadi(values):
        x = ca.vec(values)
        top = ca.mmax(x)  # its derivative is that of the active entry: LSE's gradient does not depend on it
        return top + ca.log(ca.sum1(ca.exp(sharpness * (x - top)))) / sharpness
    x = np.asarray(values, float).ravel()
    top = x.max()
    return top + np.log(np.sum(np.exp(sharpness * (x - top)))) / sharpness
