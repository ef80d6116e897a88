"""Synthetic trial folders with known truth (``gait synth``).

A periodic walking motion of the 27-DoF model: normative sagittal joint-angle
curves (Winter) with small frontal and transverse motion; the pelvis placed so
that the stance foot rolls on the floor without slipping (heel → flat → toe);
the cycle re-timed so that the body's centre of mass follows the linear inverted
pendulum over a centre-of-pressure path under the stance foot. Ground reactions
are then exactly consistent with it: the whole-body wrench ``Σ m (a + g)``,
``Σ dL/dt`` (what the ground must supply for zero pelvis residual) goes to the
stance foot in single support and is shared between the feet in double support
along the line joining their centres of pressure, each of which stays where it
is on the floor, so both feet's loads start and end at zero continuously.
Markers (Table A.6) ride rigidly on the bodies, plus white noise (RMS 3-D error
``noise_mm``) and a low-frequency skin artefact (peak 3-D displacement
``artefact_mm``). Two TYPE-2 plates in millimetres measure one right and one
left stance. ``truth/`` holds the exact kinematics, moments, GRF and events.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml
from scipy.interpolate import CubicSpline

from gaitcli.errors import InputError
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINTS, MOMENTS
from gaitcli.core.recording import ForcePlate, Markers

G = 9.81
ANALOG_RATE_HZ = 1000.0
MARKER_RATE_HZ = 100.0

@dataclass(frozen=True)
class Condition:
    """One of the dissertation's experiments (3.1.1): gait period and locked joints.

    The added masses of each condition are the presets of
    :func:`gaitcli.kinematics.anthropometry.preset_disturbances` (Tables A.2–A.3);
    the speed follows from the stride the joint angles make over the period.
    """

    name: str
    period_s: float
    locked_knee_r: bool = False
    locked_ankle_r: bool = False


# Periods grow with the kinematic constraints, as the speeds of Table 3.1 fall.
CONDITIONS = {
    "normal": Condition("normal", 1.20),
    "ankle_weight": Condition("ankle_weight", 1.24),
    "knee_orthosis": Condition("knee_orthosis", 1.30, locked_knee_r=True),
    "ankle_fixed": Condition("ankle_fixed", 1.26, locked_ankle_r=True),
    "ski_boot": Condition("ski_boot", 1.30, locked_ankle_r=True),
}

#: the marker set of Table A.6 and the body each marker rides on
MARKER_BODY = {
    "ASISr": "pelvis", "ASISl": "pelvis", "PSISr": "pelvis", "PSISl": "pelvis",
    "C7": "hat", "ST": "hat", "ACr": "hat", "ACl": "hat",
    "GTr": "thigh_r", "MRFr": "thigh_r", "LEFr": "thigh_r", "MEFr": "thigh_r",
    "TTr": "shank_r", "LMr": "shank_r", "MMr": "shank_r",
    "CAr": "foot_r", "VMr": "foot_r", "FMr": "foot_r",
    "GTl": "thigh_l", "MRFl": "thigh_l", "LEFl": "thigh_l", "MEFl": "thigh_l",
    "TTl": "shank_l", "LMl": "shank_l", "MMl": "shank_l",
    "CAl": "foot_l", "VMl": "foot_l", "FMl": "foot_l",
}


# ---------------------------------------------------------------------------------------------
# standing geometry
# ---------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Geometry:
    """Standing posture (global axes, feet on the floor z = 0, facing +x), metres."""

    landmarks: dict  # name -> (3,)
    hip: dict  # side -> (3,) joint centres
    knee: dict
    ankle: dict
    heel: dict  # side -> floor contact point under the heel
    toe: dict  # side -> floor contact point under the metatarsal heads (push-off pivot)


def standing_geometry(stature_m: float) -> Geometry:
    """The standing template of :mod:`gaitcli.kinematics.markerset` plus joint centres and floor contacts.

    Heel and toe contact points are the calcaneus and first-metatarsal markers
    projected on the floor z = 0 at the ankle's lateral position.
    """
    from gaitcli.kinematics.markerset import standing_template

    lm = standing_template(stature_m, with_virtual_joint_centres=True)
    hip, knee, ankle, heel, toe = {}, {}, {}, {}, {}
    for s in ("r", "l"):
        hip[s], knee[s], ankle[s] = lm[f"HJC{s}"], lm[f"KJC{s}"], lm[f"AJC{s}"]
        heel[s] = np.array([lm[f"CA{s}"][0], ankle[s][1], 0.0])
        toe[s] = np.array([lm[f"FM{s}"][0], ankle[s][1], 0.0])
    markers = {k: v for k, v in lm.items() if k in MARKER_BODY}
    return Geometry(landmarks=markers, hip=hip, knee=knee, ankle=ankle, heel=heel, toe=toe)


# ---------------------------------------------------------------------------------------------
# smooth profiles
# ---------------------------------------------------------------------------------------------
def smoothstep(u):
    """C3 step from 0 (u ≤ 0) to 1 (u ≥ 1): 35u⁴ − 84u⁵ + 70u⁶ − 20u⁷."""
    u = np.clip(u, 0.0, 1.0)
    return u ** 4 * (35 - 84 * u + 70 * u ** 2 - 20 * u ** 3)


def periodic_derivatives(y, period_s):
    """First and second time derivatives of samples of a periodic signal over one period (spectral)."""
    n = y.shape[0]
    k = np.fft.rfftfreq(n, d=period_s / n) * 2 * np.pi
    Y = np.fft.rfft(y, axis=0)
    shape = (-1,) + (1,) * (y.ndim - 1)
    d1 = np.fft.irfft(Y * (1j * k).reshape(shape), n=n, axis=0)
    d2 = np.fft.irfft(Y * (-(k ** 2)).reshape(shape), n=n, axis=0)
    return d1, d2


# ---------------------------------------------------------------------------------------------
# the gait design
# ---------------------------------------------------------------------------------------------
@dataclass
class GaitDesign:
    """One periodic gait cycle on a uniform grid, starting at right heel strike."""

    time_s: np.ndarray  # (N,)
    q: np.ndarray  # (N, 27) with pelvis_x including the forward trend
    stance: dict  # side -> (N,) bool
    events: list  # (phase 0..1, side, kind)
    speed_m_s: float
    period_s: float
    stride_m: float
    cop_plan_m: np.ndarray | None = None  # planned whole-body COP x with the trend v·t removed


#: normative sagittal curves (clinical signs, degrees) over the cycle from heel strike, after Winter's
#: adult walking data: (percent of cycle, angle) via points of a smooth periodic curve
HIP_FLEXION = ((0, 30), (5, 29), (10, 26), (15, 22), (20, 18), (25, 14), (30, 10), (35, 6), (40, 2), (45, -3),
               (50, -8), (55, -10), (60, -6), (65, 2), (70, 12), (75, 21), (80, 27), (85, 31), (90, 33), (95, 32))
KNEE_FLEXION = ((0, 4), (5, 10), (10, 16), (15, 19), (20, 17), (25, 14), (30, 10), (35, 7), (40, 5), (45, 6),
                (50, 9), (55, 17), (60, 30), (65, 45), (70, 58), (75, 62), (80, 56), (85, 42), (90, 24), (95, 9))
ANKLE_DORSIFLEXION = ((0, 0), (5, -4), (10, -5), (15, -1), (20, 3), (25, 5), (30, 7), (35, 8), (40, 9), (45, 10),
                      (50, 8), (55, 2), (60, -8), (65, -16), (70, -13), (75, -6), (80, -1), (85, 1), (90, 1),
                      (95, 0))
HIP_ADDUCTION = ((0, 3), (15, 7), (40, 3), (60, -3), (75, -6), (90, -1), (100, 3))
HIP_ROTATION = ((0, 2), (20, 5), (50, 0), (70, -5), (100, 2))
STANCE_END = 0.62  # toe off of the same foot, fraction of the cycle
DOUBLE_SUPPORT = 0.12
PELVIS_HARMONICS = (4, 3, 4)  # x, y, z
ROLL_RADIUS_M = 0.30
HEEL_COP_M = -0.04  # where the COP starts at heel strike, forward of the ankle centre
WARP_HARMONICS = 4


def periodic_curve(points, phase, *, harmonics=5):
    """Smooth periodic curve through (percent, value) via points, evaluated at ``phase`` (0..1).

    A periodic cubic spline through the points, low-passed to ``harmonics`` Fourier
    terms so every derivative is continuous.
    """
    pct, val = np.array(points, dtype=float).T
    if pct[-1] != 100:
        pct, val = np.append(pct, 100.0), np.append(val, val[0])
    spline = CubicSpline(pct / 100.0, val, bc_type="periodic")
    grid = np.arange(512) / 512
    coef = np.fft.rfft(spline(grid))[: harmonics + 1]
    k = np.arange(coef.size)
    phase = np.asarray(phase, dtype=float)
    terms = np.exp(2j * np.pi * np.multiply.outer(phase, k))
    scale = np.where(k == 0, 1.0, 2.0) / grid.size
    return np.real(terms @ (coef * scale))


def leg_angles(phase, side: str, condition: Condition):
    """The 9 internal leg coordinates (rad) of one side over its own phase (0 at its heel strike).

    Clinical angles are converted to the model's Cardan signs (3.1): hip flexion,
    ankle dorsiflexion are negative rotations about y; adduction and internal
    rotation are mirrored on the left.
    """
    mirror = 1.0 if side == "r" else -1.0
    hip_flex = np.radians(periodic_curve(HIP_FLEXION, phase))
    knee = np.radians(periodic_curve(KNEE_FLEXION, phase))
    ankle = np.radians(periodic_curve(ANKLE_DORSIFLEXION, phase))
    adduction = np.radians(periodic_curve(HIP_ADDUCTION, phase))
    rotation = np.radians(periodic_curve(HIP_ROTATION, phase))
    if side == "r" and condition.locked_knee_r:
        knee = np.full_like(knee, np.radians(5.0))
        # circumduction: the stiff leg swings outwards, and the hip flexes more to clear the floor
        swing = np.sin(np.pi * np.clip((phase - STANCE_END) / (1 - STANCE_END), 0, 1)) ** 2
        adduction = adduction - np.radians(8.0) * swing
        hip_flex = hip_flex + np.radians(6.0) * swing
    if side == "r" and condition.locked_ankle_r:
        ankle = np.zeros_like(ankle)
    zero = np.zeros_like(knee)
    return np.column_stack([-hip_flex, mirror * adduction, mirror * rotation,
                            knee, mirror * np.radians(2.0) * np.sin(2 * np.pi * phase), zero,
                            -ankle, mirror * np.radians(3.0) * np.sin(2 * np.pi * phase), zero])


def design_gait(geometry: Geometry, condition: Condition, params, *, samples: int | None = None,
                cop_offset_m: np.ndarray | None = None) -> GaitDesign:
    """One periodic cycle of the condition's gait, starting at right heel strike.

    Joint angles follow normative curves; the pelvis is placed so that the stance
    foot rolls on the floor without slipping (heel → metatarsal heads), and in double
    support the pelvis blends smoothly from the trailing to the leading foot's
    placement. The stride length, hence the speed, follows from the angles.
    """
    from gaitcli.kinematics.forward import forward_kinematics

    T = condition.period_s
    n = samples or int(round(T * ANALOG_RATE_HZ))
    t = np.arange(3 * n) * T / n  # three cycles: the middle one is periodic and returned
    w = 2 * np.pi / T
    q = np.zeros((t.size, 27))
    q[:, 3:6] = np.column_stack([-np.radians(3.0) * np.sin(w * t),  # obliquity: swing side drops
                                 np.radians(3.0) + np.radians(0.3) * np.cos(2 * w * t),  # anterior tilt
                                 np.radians(4.0) * np.cos(w * t)])  # right side forward at right strike
    q[:, 6:9] = np.column_stack([np.radians(2.0) + np.radians(0.3) * np.cos(2 * w * t),
                                 np.radians(2.0) * np.sin(w * t), -np.radians(5.0) * np.cos(w * t)])
    offsets = {"r": 0.0, "l": 0.5}
    for side, j0 in (("r", 9), ("l", 18)):
        q[:, j0:j0 + 9] = leg_angles(np.mod(t / T - offsets[side], 1.0), side, condition)

    # each foot rolls on the floor like a rocker: the arc of radius ROLL_RADIUS_M under the sole (a
    # roll-over shape) touches the floor below its centre, and rolling without slip moves the centre
    # forward by R·Δβ as the foot pitches toe-down by Δβ
    states = forward_kinematics(q, params)
    centre_rel, pitch = {}, {}
    for side in offsets:
        body = BODIES.index(f"foot_{side}")
        standing_com = geometry.ankle[side] - params.joint_in_child_m[JOINTS.index(f"ankle_{side}")]
        sole_mid = geometry.heel[side] + 0.45 * (geometry.toe[side] - geometry.heel[side])
        centre_local = sole_mid + np.array([0.0, 0.0, ROLL_RADIUS_M]) - standing_com
        R = states.rotation[:, body]
        centre_rel[side] = states.com_m[:, body] + np.einsum("nij,j->ni", R, centre_local)
        pitch[side] = np.unwrap(np.arctan2(-R[:, 2, 0], R[:, 0, 0]))  # toe-down rotation about y

    def foot_estimate(side, anchor, first, idx):
        """Pelvis CoM position that keeps ``side``'s rocker rolling from where it landed at ``first``."""
        centre = np.zeros((idx.size, 3))
        centre[:, 0] = anchor[0] + ROLL_RADIUS_M * (pitch[side][idx] - pitch[side][first])
        centre[:, 1] = anchor[1]
        centre[:, 2] = ROLL_RADIUS_M
        return centre - centre_rel[side][idx]

    pelvis = np.zeros((t.size, 3))
    strikes = sorted([(k * T + offsets[s] * T, s) for k in range(3) for s in offsets])
    anchors, firsts = {}, {}
    for i, (t_strike, side) in enumerate(strikes):
        first = int(round(t_strike / T * n))
        last = int(round(strikes[i + 1][0] / T * n)) if i + 1 < len(strikes) else t.size
        idx = np.arange(first, last)
        previous = -centre_rel[side][first] if i == 0 else pelvis[first - 1]
        anchors[side] = (previous + centre_rel[side][first])[:2]
        firsts[side] = first
        lead = foot_estimate(side, anchors[side], first, idx)
        if i == 0:
            pelvis[idx] = lead
            continue
        other = "l" if side == "r" else "r"
        trail = foot_estimate(other, anchors[other], firsts[other], idx)
        weight = smoothstep((t[idx] - t_strike) / (DOUBLE_SUPPORT * T))[:, None]
        pelvis[idx] = (1 - weight) * trail + weight * lead
    q[:, 0:3] = pelvis
    # the middle cycle as a function of phase; the pelvis x trend (stride per cycle) kept apart
    stride = float(pelvis[2 * n, 0] - pelvis[n, 0])
    phase = np.arange(n + 1) / n
    cycle = q[n:2 * n + 1].copy()
    cycle[:, 0] -= stride * phase + cycle[0, 0]
    cycle[:, 1] -= np.mean(cycle[:-1, 1])
    cycle[-1] = cycle[0]  # periodic to round-off (the chain is exactly periodic after one cycle)
    spline = CubicSpline(phase, cycle, bc_type="periodic", axis=0)

    # time warp: normative angle curves progress the pelvis unevenly. Re-time the cycle so that the
    # whole-body CoM follows the linear inverted pendulum over a COP path that rolls from heel to
    # metatarsal heads under the stance foot; the feet still roll without slipping, only timing changes.
    tau = np.arange(n) / n
    full = forward_kinematics(q, params)  # the three chained cycles
    shift = pelvis[n, 0]  # world x of the middle cycle's start, removed from the spline coordinates
    mass = np.asarray(params.mass_kg)
    com = np.einsum("b,nbi->ni", mass, full.com_m) / mass.sum()
    ankle_x = {s: full.joint_centre_m[:, JOINTS.index(f"ankle_{s}"), 0] - shift for s in offsets}
    middle = np.arange(n, 2 * n)
    plan = np.zeros(n)
    flat = int(0.3 * n)  # the foot-flat instant of a stance, where its ankle is planted
    for side, off in offsets.items():
        other = "l" if side == "r" else "r"
        own = np.mod(middle / n - off, 1.0)
        strike = middle - np.round(own * n).astype(int)
        planted = ankle_x[side][strike + flat]
        single = (own >= DOUBLE_SUPPORT) & (own < 0.5)
        u = (own[single] - DOUBLE_SUPPORT) / (0.5 - DOUBLE_SUPPORT)
        plan[single] = planted[single] - 0.04 + 0.17 * u
        trailing = (own >= 0.5) & (own < STANCE_END)
        u = (own[trailing] - 0.5) / DOUBLE_SUPPORT
        lead = ankle_x[other][strike[trailing] + n // 2 + flat] - 0.04
        plan[trailing] = planted[trailing] + 0.13 + (lead - planted[trailing] - 0.13) * u
    cop_plan = plan - stride * tau
    detrended_plan = cop_plan if cop_offset_m is None else cop_plan + cop_offset_m
    omega2 = G / float(np.mean(com[middle, 2]))
    k = np.fft.rfftfreq(n, d=T / n) * 2 * np.pi
    target = np.fft.irfft(np.fft.rfft(detrended_plan) * omega2 / (omega2 + k ** 2), n=n) + stride * tau
    # invert com_x(φ) (monotonic) at the targets, over three cycles to handle the wrap
    com_x = com[:, 0] - shift
    phases = np.arange(3 * n) / n - 1.0
    warped = np.interp(target, com_x, phases)
    spectrum = np.fft.rfft(warped - tau)
    spectrum[WARP_HARMONICS + 1:] = 0.0
    warped = tau + np.fft.irfft(spectrum, n=n)
    q = spline(np.mod(warped, 1.0))
    q[:, 0] += stride * warped
    # sideways, the CoM follows the inverted pendulum over the stance foot as well: the pelvis is moved
    # sideways by the difference (a centimetre or two of sideways foot slip, which the truth carries)
    states = forward_kinematics(q, params)
    com_y = np.einsum("b,nb->n", mass, states.com_m[:, :, 1]) / mass.sum()
    ankle_y = {s: states.joint_centre_m[:, JOINTS.index(f"ankle_{s}"), 1] for s in offsets}
    own = {s: np.mod(warped - off, 1.0) for s, off in offsets.items()}
    plan_y = np.zeros(n)
    for side in offsets:
        other = "l" if side == "r" else "r"
        single = (own[side] >= DOUBLE_SUPPORT) & (own[side] < 0.5)
        plan_y[single] = np.mean(ankle_y[side][single])
        trailing = (own[side] >= 0.5) & (own[side] < STANCE_END)
        u = (own[side][trailing] - 0.5) / DOUBLE_SUPPORT
        plan_y[trailing] = np.mean(ankle_y[side][single]) * (1 - u) + np.mean(ankle_y[other][
            (own[other] >= DOUBLE_SUPPORT) & (own[other] < 0.5)]) * u
    target_y = np.fft.irfft(np.fft.rfft(plan_y) * omega2 / (omega2 + k ** 2), n=n)
    q[:, 1] += target_y - com_y
    # the two feet's placements disagree a little in double support (normative angles are not an exact
    # closed chain); keeping the first harmonics of the pelvis path removes the blend's jerk at the cost
    # of a few millimetres of foot slip
    detrended = q[:, 0:3] - np.outer(tau, [stride, 0.0, 0.0])
    spectrum = np.fft.rfft(detrended, axis=0)
    for axis, keep in enumerate(PELVIS_HARMONICS):
        spectrum[keep + 1:, axis] = 0.0
    q[:, 0:3] = np.fft.irfft(spectrum, n=n, axis=0) + np.outer(tau, [stride, 0.0, 0.0])

    stance = {s: np.mod(warped - offsets[s], 1.0) < STANCE_END for s in offsets}
    unwrapped = np.concatenate([warped - 1, warped, warped + 1])
    taus = np.concatenate([tau - 1, tau, tau + 1])
    events = []
    for at, side, kind in ((0.0, "r", "heel_strike"), (DOUBLE_SUPPORT, "l", "toe_off"),
                           (0.5, "l", "heel_strike"), (0.5 + DOUBLE_SUPPORT, "r", "toe_off")):
        events.append((float(np.mod(np.interp(at, unwrapped, taus), 1.0)), side, kind))
    return GaitDesign(time_s=tau * T, q=q, stance=stance, events=events, speed_m_s=stride / T, period_s=T,
                      stride_m=stride, cop_plan_m=cop_plan)


def balanced_gait(geometry: Geometry, condition: Condition, params, *, iterations: int = 4) -> GaitDesign:
    """:func:`design_gait`, re-timed until the whole-body COP follows the planned heel → toe path.

    The pendulum model ignores the segments' angular momentum; each pass measures
    how far the true COP (from :func:`ground_reactions`) runs ahead of the plan and
    shifts the plan the other way.
    """
    design = design_gait(geometry, condition, params)
    offset = np.zeros(design.q.shape[0])
    for _ in range(iterations):
        _, _, _, _, cop, plan = ground_reactions(design, params, with_plan=True)
        offset -= cop[:, 0] - plan
        design = design_gait(geometry, condition, params, cop_offset_m=offset)
    return design


# ---------------------------------------------------------------------------------------------
# ground reactions consistent with the motion
# ---------------------------------------------------------------------------------------------
def whole_body_cop(force, moment):
    """COP on the floor z = 0 and vertical free moment of a wrench given about the global origin."""
    cop = np.zeros_like(force)
    cop[:, 0] = -moment[:, 1] / force[:, 2]
    cop[:, 1] = moment[:, 0] / force[:, 2]
    free = moment[:, 2] - (cop[:, 0] * force[:, 1] - cop[:, 1] * force[:, 0])
    return cop, free


def split_between_feet(design: GaitDesign, force, cop, free, hips=None, ankles=None):
    """Per-foot force (N), COP (m) and free moment (N·m) summing exactly to the whole-body wrench.

    ``cop`` is the whole-body COP with the forward trend ``v t`` removed (periodic).
    Single support: all on the stance foot. Double support: the whole-body COP is
    projected on the line from the trailing foot's COP at the leading foot's
    strike to the leading foot's COP at the trailing foot's toe-off; the share
    ``λ`` along that line splits force and free moment, and the offset from the
    line moves both feet's COPs, so ``Σ λ_i c_i = c`` and each load starts and
    ends at zero. Returns ``(per_foot, clip)``; ``clip`` (how far λ had to be
    clipped into [0, 1]) is 0 when the split is exact.

    With ``hips`` (side -> (n, 3) hip centres, trend removed), the feet also push
    against each other as legs do in double support — the leading foot braking, the
    trailing one propelling: an internal force pair along the line joining their
    COPs (which adds no moment) turns each foot's force towards its hip, with the
    mismatch to the total fore-aft force shared by ``λ``.
    """
    n = force.shape[0]
    out = {s: {"force_N": np.zeros((n, 3)), "cop_m": np.full((n, 3), np.nan), "free_moment_Nm": np.zeros(n)}
           for s in "rl"}
    both = design.stance["r"] & design.stance["l"]
    for s in "rl":
        only = design.stance[s] & ~both
        out[s]["force_N"][only] = force[only]
        out[s]["cop_m"][only] = cop[only]
        out[s]["free_moment_Nm"][only] = free[only]
    clip = 0.0
    runs = np.flatnonzero(np.diff(np.concatenate([[both[-1]], both]).astype(int)) == 1)  # run starts
    for first in runs:
        length = int(np.argmin(np.roll(both, -first)))  # samples until the run ends
        idx = (first + np.arange(length)) % n
        lead = "r" if not design.stance["r"][(first - 1) % n] else "l"  # the foot that just landed
        trail = "l" if lead == "r" else "r"
        # a point fixed on the floor moves backwards at the walking speed in these detrended
        # coordinates: the trailing foot's COP stays where single support left it, the leading
        # foot's where single support will take it over
        steps = np.arange(idx.size)[:, None]
        backwards = np.array([design.speed_m_s * design.period_s / n, 0.0, 0.0])
        c_trail = cop[(idx[0] - 1) % n] - (steps + 1) * backwards
        c_lead = cop[(idx[-1] + 1) % n] + (idx.size - steps) * backwards
        if ankles is not None:  # the leading foot's COP rolls in from under its heel
            u = (steps + 1) / (idx.size + 1)
            heel = ankles[lead][idx[0]] + np.array([HEEL_COP_M, 0.0, 0.0])
            heel[2] = 0.0
            c_lead = heel - steps * backwards + u * (c_lead - heel + steps * backwards)
        line = c_lead - c_trail
        lam = np.sum((cop[idx] - c_trail) * line, axis=1) / np.sum(line * line, axis=1)
        clip = max(clip, float(np.max(np.abs(lam - np.clip(lam, 0, 1)))))
        lam = np.clip(lam, 0.0, 1.0)
        offset = cop[idx] - (c_trail + lam[:, None] * line)
        out[lead]["force_N"][idx] = lam[:, None] * force[idx]
        out[trail]["force_N"][idx] = (1 - lam)[:, None] * force[idx]
        out[lead]["free_moment_Nm"][idx] = lam * free[idx]
        out[trail]["free_moment_Nm"][idx] = (1 - lam) * free[idx]
        out[lead]["cop_m"][idx] = c_lead + offset
        out[trail]["cop_m"][idx] = c_trail + offset
        if hips is not None:
            along = {}
            for side in (lead, trail):
                lever = hips[side][idx] - out[side]["cop_m"][idx]
                along[side] = out[side]["force_N"][idx, 2] * lever[:, 0] / lever[:, 2]  # fore-aft along the leg
            mismatch = force[idx, 0] - along[lead] - along[trail]
            push_x = along[lead] + lam * mismatch - lam * force[idx, 0]  # internal part on the leading foot
            line_xy = out[lead]["cop_m"][idx, :2] - out[trail]["cop_m"][idx, :2]
            push = np.column_stack([push_x, push_x * line_xy[:, 1] / line_xy[:, 0], np.zeros(idx.size)])
            out[lead]["force_N"][idx] += push
            out[trail]["force_N"][idx] -= push
    return out, clip


def ground_reactions(design: GaitDesign, params, *, gravity_m_s2: float = G, with_plan: bool = False):
    """Exact derivatives of the designed cycle and the per-foot ground reactions consistent with it.

    Returns ``(qd, qdd, feet, clip)`` with ``feet[side]`` holding ``force_N``,
    ``cop_m`` (trend removed, NaN in swing) and ``free_moment_Nm`` over the cycle.
    """
    from gaitcli.dynamics.inverse import required_external_wrench
    from gaitcli.kinematics.forward import forward_kinematics

    trend = design.speed_m_s * design.time_s
    periodic = design.q.copy()
    periodic[:, 0] -= trend
    qd, qdd = periodic_derivatives(periodic, design.period_s)
    qd[:, 0] += design.speed_m_s
    force, moment = required_external_wrench(design.q, qd, qdd, params, gravity_m_s2=gravity_m_s2)
    cop, free = whole_body_cop(force, moment)
    cop[:, 0] -= trend
    joints = forward_kinematics(design.q, params).joint_centre_m
    hips = {s: joints[:, JOINTS.index(f"hip_{s}")] - np.outer(trend, [1.0, 0.0, 0.0]) for s in "rl"}
    ankles = {s: joints[:, JOINTS.index(f"ankle_{s}")] - np.outer(trend, [1.0, 0.0, 0.0]) for s in "rl"}
    feet, clip = split_between_feet(design, force, cop, free, hips, ankles)
    if with_plan:
        return qd, qdd, feet, clip, cop, design.cop_plan_m
    return qd, qdd, feet, clip


# ---------------------------------------------------------------------------------------------
# a whole trial folder
# ---------------------------------------------------------------------------------------------
@dataclass
class SyntheticTrial:
    """Everything ``make_trial`` wrote, in memory (model axes, SI)."""

    markers: Markers
    static: Markers
    plates: list
    q: np.ndarray  # (frames, 27) at the marker rate
    qd: np.ndarray
    qdd: np.ndarray
    feet: dict  # side -> force_N, cop_m, free_moment_Nm at the marker rate (all contacts)
    plate_feet: list  # side of each plate
    events: list  # (time_s, frame, side, kind, on_plate)
    calibration: object
    design: GaitDesign
    joint_moments_Nm: np.ndarray  # (frames, 7, 3) in the distal segment frame
    split_clip: float


def _skin_artefact(rng, n_markers, time_s, period_s, amplitude_m, bodies):
    """Low-frequency skin artefact of peak 3-D displacement ``amplitude_m``, at the gait frequency and its
    first harmonic: per segment a common part (70 %) plus a per-marker part (30 %)."""
    w = 2 * np.pi / period_s
    out = np.zeros((time_s.size, n_markers, 3))
    common = {}
    for body in sorted(set(bodies)):  # a fixed order: the same seed gives the same trial
        phases = rng.uniform(0, 2 * np.pi, (2, 3))
        common[body] = 0.6 * np.sin(w * time_s[:, None] + phases[0]) + 0.4 * np.sin(2 * w * time_s[:, None]
                                                                                  + phases[1])
    for i, body in enumerate(bodies):
        phases = rng.uniform(0, 2 * np.pi, (2, 3))
        own = 0.6 * np.sin(w * time_s[:, None] + phases[0]) + 0.4 * np.sin(2 * w * time_s[:, None] + phases[1])
        out[:, i] = amplitude_m / np.sqrt(3.0) * (0.7 * common[body] + 0.3 * own)  # ≤ amplitude in 3-D
    return out


def simulate_trial(*, condition: str = "normal", seed: int = 0, noise_mm: float = 2.0, artefact_mm: float = 10.0,
                   strides: int = 3, mass_kg: float = 75.0, stature_m: float = 1.78, sex: str = "male",
                   plate_noise_N: float = 1.0, period_s: float | None = None) -> SyntheticTrial:
    """Make a synthetic walking trial with known truth (nothing written).

    ``noise_mm`` is the RMS of each marker's 3-D position error (white, σ = noise/√3
    per axis), as optical systems quote their accuracy; ``artefact_mm`` the peak
    3-D displacement of the low-frequency skin artefact. ``period_s`` (gait cycle, s)
    defaults to the condition's; the stride length follows from stature and angles.
    """
    from gaitcli.dynamics.equations import ExternalWrench
    from gaitcli.dynamics.inverse import inverse_dynamics
    from gaitcli.kinematics.calibration import calibrate
    from gaitcli.kinematics.forward import marker_positions
    from gaitcli.kinematics.markerset import SEGMENT_MARKERS, landmarks_to_markers, standing_template

    if condition not in CONDITIONS:
        raise InputError(None, "--condition", f"got {condition!r} (expected one of {', '.join(CONDITIONS)})")
    if noise_mm < 0 or artefact_mm < 0:
        raise InputError(None, "--noise-mm", "expected noise and artefact amplitudes ≥ 0 mm")
    cond = CONDITIONS[condition]
    if period_s is not None:
        if not 0.6 <= period_s <= 3.0:
            raise InputError(None, "--period-s", f"got {period_s} s (expected a gait cycle of 0.6–3.0 s)")
        cond = replace(cond, period_s=float(period_s))
    rng = np.random.default_rng(seed)
    template = {k: v for k, v in standing_template(stature_m).items() if k in MARKER_BODY}
    exact_static = landmarks_to_markers(template, rate_hz=MARKER_RATE_HZ)
    cal = calibrate(exact_static, mass_kg=mass_kg, stature_m=stature_m, sex=sex,
                    disturbances=() if condition == "normal" else (condition,))
    params = cal.body
    jc = cal.joint_centres_m
    geometry = Geometry(
        landmarks=template,
        hip={s: jc[f"HJC{s}"] for s in "rl"}, knee={s: jc[f"KJC{s}"] for s in "rl"},
        ankle={s: jc[f"AJC{s}"] for s in "rl"},
        heel={s: np.array([template[f"CA{s}"][0], jc[f"AJC{s}"][1], 0.0]) for s in "rl"},
        toe={s: np.array([template[f"FM{s}"][0], jc[f"AJC{s}"][1], 0.0]) for s in "rl"})
    design = balanced_gait(geometry, cond, params)
    qd_c, qdd_c, feet_c, clip = ground_reactions(design, params)

    # tile the cycle over the trial at the analog rate; markers every `step` analog samples
    T, n = design.period_s, design.q.shape[0]
    step = int(round(ANALOG_RATE_HZ / MARKER_RATE_HZ))
    first, last = int(round(0.25 * n)), int(round((strides + 1.25) * n))
    j = np.arange(first, last)
    cycle, i = j // n, j % n
    t_abs = j / ANALOG_RATE_HZ
    t = t_abs - t_abs[0]
    q = design.q[i].copy()
    q[:, 0] += cycle * design.stride_m
    qd, qdd = qd_c[i], qdd_c[i]
    feet = {}
    for s in "rl":
        cop = feet_c[s]["cop_m"][i].copy()
        cop[:, 0] += design.speed_m_s * t_abs
        feet[s] = {"force_N": feet_c[s]["force_N"][i], "cop_m": cop, "free_moment_Nm": feet_c[s]["free_moment_Nm"][i]}

    # contacts: (side, first, last analog index) of every stance in the window
    contacts = []
    for s in "rl":
        on = design.stance[s][i].astype(int)
        edges = np.flatnonzero(np.diff(np.concatenate([[0], on, [0]])))
        contacts += [(s, a, b) for a, b in zip(edges[::2], edges[1::2])]
    complete = sorted([c for c in contacts if c[1] > 0 and c[2] < j.size], key=lambda c: c[1])
    middle = len(complete) // 2 - 1
    chosen = complete[middle:middle + 2]  # one right and one left stance in the middle of the walk

    plates = []
    plate_feet = []
    for k, (side, a, b) in enumerate(chosen):
        centre = np.nanmean(feet[side]["cop_m"][a:b], axis=0)
        centre[2] = 0.0
        half = np.array([0.3, 0.2])
        corners = centre + np.array([[half[0], -half[1], 0], [-half[0], -half[1], 0],
                                     [-half[0], half[1], 0], [half[0], half[1], 0]])
        force = np.zeros((j.size, 3))
        moment = np.zeros((j.size, 3))
        force[a:b] = feet[side]["force_N"][a:b]
        lever = np.nan_to_num(feet[side]["cop_m"][a:b] - centre)
        moment[a:b] = np.cross(lever, force[a:b])
        moment[a:b, 2] += feet[side]["free_moment_Nm"][a:b]
        force += rng.normal(0.0, plate_noise_N, force.shape)
        moment += rng.normal(0.0, plate_noise_N * 0.05, moment.shape)
        plates.append(ForcePlate(name=f"plate{k + 1}", force_N=force, moment_Nm=moment, centre_m=centre,
                                 corners_m=corners, rate_hz=ANALOG_RATE_HZ))
        plate_feet.append(side)

    # markers
    frames = slice(0, None, step)
    qm = q[frames]
    in_body, labels = cal.markers_in_body()
    wanted = {bi: [k for k, name in enumerate(labels[bi]) if name in SEGMENT_MARKERS[BODIES[bi]]]
              for bi in in_body}
    positions = marker_positions(qm, params, {bi: in_body[bi][wanted[bi]] for bi in in_body})
    names, columns, bodies = [], [], []
    for bi in in_body:
        for col, k in enumerate(wanted[bi]):
            names.append(labels[bi][k])
            columns.append(positions[bi][:, col])
            bodies.append(BODIES[bi])
    exact = np.stack(columns, axis=1)
    tm = t[frames]
    noisy = exact + rng.normal(0.0, noise_mm / 1000.0 / np.sqrt(3.0), exact.shape) \
        + _skin_artefact(rng, len(names), tm, T, artefact_mm / 1000.0, bodies)
    markers = Markers(tuple(names), noisy, MARKER_RATE_HZ)
    static_positions = np.stack([template[nm] for nm in names])[None] \
        + rng.normal(0.0, noise_mm / 1000.0 / np.sqrt(3.0), (int(MARKER_RATE_HZ), len(names), 3))
    static = Markers(tuple(names), static_positions, MARKER_RATE_HZ)

    # truth: moments with every ground contact (not only the plates), at the marker rate
    external = [ExternalWrench(body=BODIES.index(f"foot_{s}"), force_N=feet[s]["force_N"][frames],
                               point_m=np.nan_to_num(feet[s]["cop_m"][frames]),
                               moment_Nm=np.column_stack([np.zeros((tm.size, 2)),
                                                          feet[s]["free_moment_Nm"][frames]]))
                for s in "rl"]
    result = inverse_dynamics(qm, qd[frames], qdd[frames], params, external)
    events = []
    for side, a, b in contacts:
        on_plate = (side, a, b) in chosen
        if a > 0:
            events.append((float(t[a]), int(round(t[a] * MARKER_RATE_HZ)), side, "heel_strike", on_plate))
        if b < j.size:
            events.append((float(t[b - 1]), int(round(t[b - 1] * MARKER_RATE_HZ)), side, "toe_off", on_plate))
    events.sort()
    sub_feet = {s: {k: v[frames] for k, v in feet[s].items()} for s in "rl"}
    return SyntheticTrial(markers=markers, static=static, plates=plates, q=qm, qd=qd[frames], qdd=qdd[frames],
                          feet=sub_feet, plate_feet=plate_feet, events=events, calibration=cal, design=design,
                          joint_moments_Nm=result.joint_moments_distal_Nm, split_clip=clip)


def subject_yaml(trial: SyntheticTrial, *, condition: str, mass_kg: float, stature_m: float, sex: str) -> dict:
    """The trial's ``subject.yaml``: the subject, and the condition's added masses written out."""
    from gaitcli.kinematics.anthropometry import preset_disturbances

    data = {"mass_kg": mass_kg, "stature_m": stature_m, "sex": sex, "condition": condition}
    if condition != "normal":
        data["disturbed_side"] = "r"
        data["disturbances"] = [
            {"segment": d.segment, "name": d.name, "mass_kg": round(float(d.mass_kg), 6),
             "inertia_kgm2": [round(float(x), 8) for x in np.diag(np.asarray(d.inertia_kgm2))],
             "com_offset_m": [round(float(x), 6) for x in d.com_offset_m]}
            for d in preset_disturbances(condition, trial.calibration.segments, side="r")]
    return data


def write_trial(out_dir: str | Path, *, condition: str = "normal", seed: int = 0, noise_mm: float = 2.0,
                artefact_mm: float = 10.0, plate_noise_N: float = 1.0, strides: int = 3, mass_kg: float = 75.0,
                stature_m: float = 1.78, sex: str = "male", period_s: float | None = None) -> SyntheticTrial:
    """``gait synth``: write a trial folder with trial.c3d, static.c3d, subject.yaml and truth/."""
    from gaitcli.io.atomic import atomic_path
    from gaitcli.io.c3d_write import write_c3d
    from gaitcli.io.outputs import write_table
    from gaitcli.kinematics.conventions import coordinates_to_clinical, moments_to_clinical

    trial = simulate_trial(condition=condition, seed=seed, noise_mm=noise_mm, artefact_mm=artefact_mm,
                           plate_noise_N=plate_noise_N, strides=strides, mass_kg=mass_kg, stature_m=stature_m,
                           sex=sex, period_s=period_s)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_c3d(out / "trial.c3d", trial.markers, trial.plates)
    write_c3d(out / "static.c3d", trial.static, [])
    with atomic_path(out / "subject.yaml") as tmp:
        tmp.write_text("# written by `gait synth`; the truth is in truth/\n" + yaml.safe_dump(
            subject_yaml(trial, condition=condition, mass_kg=mass_kg, stature_m=stature_m, sex=sex),
            sort_keys=False))
    time_s = trial.markers.time_s
    kin = coordinates_to_clinical(trial.q)
    write_table(out / "truth" / "kinematics.csv", {"time_s": time_s, **{c: kin[:, k] for k, c in
                                                                       enumerate(COORDINATES)}})
    mom = moments_to_clinical(trial.joint_moments_Nm)
    write_table(out / "truth" / "joint_moments.csv", {"time_s": time_s, **{c: mom[:, k] for k, c in
                                                                          enumerate(MOMENTS)}})
    grf = {"time_s": time_s}
    for s in "rl":
        for k, a in enumerate("xyz"):
            grf[f"foot_{s}_force_{a}_N"] = trial.feet[s]["force_N"][:, k]
        for k, a in enumerate("xyz"):
            grf[f"foot_{s}_cop_{a}_m"] = trial.feet[s]["cop_m"][:, k]
        grf[f"foot_{s}_free_moment_Nm"] = trial.feet[s]["free_moment_Nm"]
    write_table(out / "truth" / "grf.csv", grf)
    ev = trial.events
    write_table(out / "truth" / "events.csv", {"time_s": [e[0] for e in ev], "frame": [e[1] + 1 for e in ev],
                                               "side": [e[2] for e in ev], "event": [e[3] for e in ev],
                                               "on_plate": [int(e[4]) for e in ev]})
    write_table(out / "truth" / "plates.csv", {"plate": [p.name for p in trial.plates], "foot": trial.plate_feet})
    return trial
