"""The designed gait: one periodic walking cycle of the 27-DoF model.

Normative sagittal joint-angle curves (Winter) with small frontal and transverse
motion; the pelvis placed so that the stance foot rolls on the floor without
slipping (heel → flat → toe); the cycle re-timed so that the body's centre of
mass follows the linear inverted pendulum ``ẍ = ω² (x − p)``, ``ω² = g / z``,
over a centre-of-pressure path ``p`` under the stance foot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.kinematics.conventions import SIGNS
from gaitcli.kinematics.model import BODIES, JOINTS
from gaitcli.synth.ground import ground_reactions

#: the design grid's rate, Hz: one sample per analog (force plate) sample of the trial
ANALOG_RATE_HZ = 1000.0


@dataclass(frozen=True)
class Condition:
    """One of the dissertation's experiments (3.1.1): gait period and locked joints.

    The added masses of each condition are the presets of
    :func:`gaitcli.kinematics.disturbances.preset_disturbances` (Tables A.2–A.3);
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


@dataclass(frozen=True)
class Geometry:
    """Standing floor contacts and ankle centres (global axes, feet on the floor z = 0, facing +x), metres."""

    ankle: dict  # side -> (3,) joint centre
    heel: dict  # side -> floor contact point under the heel
    toe: dict  # side -> floor contact point under the metatarsal heads (push-off pivot)

    @classmethod
    def standing(cls, markers: dict, joint_centres_m: dict) -> Geometry:
        """From the standing markers and joint centres: the calcaneus and first-metatarsal markers
        projected on the floor z = 0 at the ankle's lateral position."""
        ankle = {s: joint_centres_m[f"AJC{s}"] for s in "rl"}
        return cls(ankle=ankle,
                   heel={s: np.array([markers[f"CA{s}"][0], ankle[s][1], 0.0]) for s in "rl"},
                   toe={s: np.array([markers[f"FM{s}"][0], ankle[s][1], 0.0]) for s in "rl"})


def smoothstep(u):
    """C3 step from 0 (u ≤ 0) to 1 (u ≥ 1): 35u⁴ − 84u⁵ + 70u⁶ − 20u⁷."""
    u = np.clip(u, 0.0, 1.0)
    return u ** 4 * (35 - 84 * u + 70 * u ** 2 - 20 * u ** 3)


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

    The angles are designed in clinical signs (both sides alike) and converted to
    the model's Cardan signs (3.1) by the sign table of
    :mod:`gaitcli.kinematics.conventions`: model = sign · clinical.
    """
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
    clinical = np.column_stack([hip_flex, adduction, rotation,
                                knee, np.radians(2.0) * np.sin(2 * np.pi * phase), zero,
                                ankle, np.radians(3.0) * np.sin(2 * np.pi * phase), zero])
    legs = [JOINTS.index(f"{j}_{side}") for j in ("hip", "knee", "ankle")]
    return clinical * SIGNS[legs].reshape(-1)


#: where each foot's heel strike falls in the cycle (fraction), the cycle starting at right heel strike
HEEL_STRIKE_PHASE = {"r": 0.0, "l": 0.5}


def design_gait(geometry: Geometry, condition: Condition, params, *, samples: int | None = None,
                cop_offset_m: np.ndarray | None = None) -> GaitDesign:
    """One periodic cycle of the condition's gait, starting at right heel strike.

    Joint angles follow normative curves; the pelvis is placed so that the stance
    foot rolls on the floor without slipping (heel → metatarsal heads), and in double
    support the pelvis blends smoothly from the trailing to the leading foot's
    placement. The stride length, hence the speed, follows from the angles.
    ``cop_offset_m`` (samples,) shifts the planned COP path (m, :func:`balanced_gait`).
    """
    T = condition.period_s
    n = samples or int(round(T * ANALOG_RATE_HZ))
    t = np.arange(3 * n) * T / n  # three cycles: the middle one is periodic and returned
    q = designed_angles(t, condition)
    q[:, 0:3] = rolling_pelvis_path(q, t, n, geometry, params, T)
    stride, spline = periodic_cycle(q, n)
    tau = np.arange(n) / n
    warped, cop_plan, omega2 = pendulum_time_warp(q, params, n, T, stride, cop_offset_m)
    q = spline(np.mod(warped, 1.0))
    q[:, 0] += stride * warped
    q[:, 1] += sideways_pendulum_shift(q, params, warped, omega2, T)
    # the two feet's placements disagree a little in double support (normative angles are not an exact
    # closed chain); keeping the first harmonics of the pelvis path removes the blend's jerk at the cost
    # of a few millimetres of foot slip
    q[:, 0:3] = low_pass_pelvis(q[:, 0:3], tau, stride)
    stance = {s: np.mod(warped - HEEL_STRIKE_PHASE[s], 1.0) < STANCE_END for s in HEEL_STRIKE_PHASE}
    return GaitDesign(time_s=tau * T, q=q, stance=stance, events=cycle_events(warped, tau), speed_m_s=stride / T,
                      period_s=T, stride_m=stride, cop_plan_m=cop_plan)


def designed_angles(time_s: np.ndarray, condition: Condition) -> np.ndarray:
    """(N, 27) coordinates over ``time_s`` (s) with the pelvis position zero: the pelvis's obliquity, tilt and
    rotation and the lumbar angles as sinusoids of the gait frequency, and each leg's normative angles
    (:func:`leg_angles`) from its own heel strike, rad."""
    T = condition.period_s
    t = time_s
    w = 2 * np.pi / T
    q = np.zeros((t.size, 27))
    q[:, 3:6] = np.column_stack([-np.radians(3.0) * np.sin(w * t),  # obliquity: swing side drops
                                 np.radians(3.0) + np.radians(0.3) * np.cos(2 * w * t),  # anterior tilt
                                 np.radians(4.0) * np.cos(w * t)])  # right side forward at right strike
    q[:, 6:9] = np.column_stack([np.radians(2.0) + np.radians(0.3) * np.cos(2 * w * t),
                                 np.radians(2.0) * np.sin(w * t), -np.radians(5.0) * np.cos(w * t)])
    for side, j0 in (("r", 9), ("l", 18)):
        q[:, j0:j0 + 9] = leg_angles(np.mod(t / T - HEEL_STRIKE_PHASE[side], 1.0), side, condition)
    return q


def rocker_centres(q: np.ndarray, geometry: Geometry, params) -> tuple[dict, dict]:
    """Each foot's rocker over ``q`` (pelvis at the origin): the centre (N, 3) m of the arc of radius
    ``ROLL_RADIUS_M`` under its sole relative to the pelvis, and the foot's toe-down pitch about y (N,) rad.

    The arc (a roll-over shape) touches the floor below its centre at 45 % of the heel → metatarsal-heads sole.
    """
    from gaitcli.kinematics.forward import forward_kinematics

    states = forward_kinematics(q, params)
    centre_rel, pitch = {}, {}
    for side in HEEL_STRIKE_PHASE:
        body = BODIES.index(f"foot_{side}")
        standing_com = geometry.ankle[side] - params.joint_in_child_m[JOINTS.index(f"ankle_{side}")]
        sole_mid = geometry.heel[side] + 0.45 * (geometry.toe[side] - geometry.heel[side])
        centre_local = sole_mid + np.array([0.0, 0.0, ROLL_RADIUS_M]) - standing_com
        R = states.rotation[:, body]
        centre_rel[side] = states.com_m[:, body] + np.einsum("nij,j->ni", R, centre_local)
        pitch[side] = np.unwrap(np.arctan2(-R[:, 2, 0], R[:, 0, 0]))  # toe-down rotation about y
    return centre_rel, pitch


def pelvis_over_rocker(centre_rel: np.ndarray, pitch: np.ndarray, anchor: np.ndarray, first: int,
                       idx: np.ndarray) -> np.ndarray:
    """Pelvis positions (len(idx), 3) m that keep one foot's rocker rolling without slip from where it landed:
    its centre at ``anchor`` (x, y) and ``ROLL_RADIUS_M`` high at sample ``first``, moved forward by R·Δβ as the
    foot pitches toe-down by Δβ."""
    centre = np.zeros((idx.size, 3))
    centre[:, 0] = anchor[0] + ROLL_RADIUS_M * (pitch[idx] - pitch[first])
    centre[:, 1] = anchor[1]
    centre[:, 2] = ROLL_RADIUS_M
    return centre - centre_rel[idx]


def rolling_pelvis_path(q: np.ndarray, t: np.ndarray, n: int, geometry: Geometry, params, T: float) -> np.ndarray:
    """The pelvis position (N, 3) m over the three cycles of ``q``: each stance foot rolls without slipping from
    its heel strike (:func:`pelvis_over_rocker`), and over the double support (``DOUBLE_SUPPORT`` of the cycle)
    the pelvis blends from the trailing foot's placement to the leading one's by :func:`smoothstep`."""
    centre_rel, pitch = rocker_centres(q, geometry, params)
    pelvis = np.zeros((t.size, 3))
    strikes = sorted([(k * T + HEEL_STRIKE_PHASE[s] * T, s) for k in range(3) for s in HEEL_STRIKE_PHASE])
    anchors, firsts = {}, {}
    for i, (t_strike, side) in enumerate(strikes):
        first = int(round(t_strike / T * n))
        last = int(round(strikes[i + 1][0] / T * n)) if i + 1 < len(strikes) else t.size
        idx = np.arange(first, last)
        previous = -centre_rel[side][first] if i == 0 else pelvis[first - 1]
        anchors[side] = (previous + centre_rel[side][first])[:2]
        firsts[side] = first
        lead = pelvis_over_rocker(centre_rel[side], pitch[side], anchors[side], first, idx)
        if i == 0:
            pelvis[idx] = lead
            continue
        other = "l" if side == "r" else "r"
        trail = pelvis_over_rocker(centre_rel[other], pitch[other], anchors[other], firsts[other], idx)
        weight = smoothstep((t[idx] - t_strike) / (DOUBLE_SUPPORT * T))[:, None]
        pelvis[idx] = (1 - weight) * trail + weight * lead
    return pelvis


def periodic_cycle(q: np.ndarray, n: int) -> tuple[float, CubicSpline]:
    """The middle of three chained cycles of ``q`` (n samples each): the stride (m, pelvis x gained over it) and
    the cycle as a periodic spline of phase (0..1), the pelvis x trend removed and y centred."""
    stride = float(q[2 * n, 0] - q[n, 0])
    phase = np.arange(n + 1) / n
    cycle = q[n:2 * n + 1].copy()
    cycle[:, 0] -= stride * phase + cycle[0, 0]
    cycle[:, 1] -= np.mean(cycle[:-1, 1])
    cycle[-1] = cycle[0]  # periodic to round-off (the chain is exactly periodic after one cycle)
    return stride, CubicSpline(phase, cycle, bc_type="periodic", axis=0)


def inverted_pendulum_com(cop_m: np.ndarray, omega2: float, T: float) -> np.ndarray:
    """The periodic CoM path (m) of the linear inverted pendulum ``ẍ = ω² (x − p)`` over a periodic COP path
    ``p`` = ``cop_m`` sampled uniformly over the cycle of ``T`` s: ``X(k) = ω² P(k) / (ω² + k²)`` per harmonic."""
    n = cop_m.size
    k = np.fft.rfftfreq(n, d=T / n) * 2 * np.pi
    return np.fft.irfft(np.fft.rfft(cop_m) * omega2 / (omega2 + k ** 2), n=n)


def forward_cop_plan(ankle_x: dict, n: int) -> np.ndarray:
    """The planned whole-body COP x (n,) m over the middle cycle, in the coordinates of ``ankle_x`` (each side's
    ankle x over three cycles): in single support it rolls under the stance foot from 4 cm behind its ankle at
    foot flat to 13 cm ahead, and in double support on to 4 cm behind the leading foot's."""
    middle = np.arange(n, 2 * n)
    plan = np.zeros(n)
    flat = int(0.3 * n)  # the foot-flat instant of a stance, where its ankle is planted
    for side, off in HEEL_STRIKE_PHASE.items():
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
    return plan


def pendulum_time_warp(q: np.ndarray, params, n: int, T: float, stride: float,
                       cop_offset_m: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, float]:
    """Re-time the cycle so that the whole-body CoM follows the linear inverted pendulum (``ω² = g / z``, z the
    CoM's mean height) over the planned COP path (:func:`forward_cop_plan`, plus ``cop_offset_m``).

    Normative angle curves progress the pelvis unevenly; the feet still roll without slipping, only timing
    changes. Returns the warped phase of each output sample (n,) (its first ``WARP_HARMONICS`` harmonics), the
    planned COP x with the trend v·t removed (n,) m, and ω² (1/s²).
    """
    from gaitcli.kinematics.forward import forward_kinematics

    tau = np.arange(n) / n
    full = forward_kinematics(q, params)  # the three chained cycles
    shift = q[n, 0]  # world x of the middle cycle's start, removed from the spline coordinates
    mass = np.asarray(params.mass_kg)
    com = np.einsum("b,nbi->ni", mass, full.com_m) / mass.sum()
    ankle_x = {s: full.joint_centre_m[:, JOINTS.index(f"ankle_{s}"), 0] - shift for s in HEEL_STRIKE_PHASE}
    cop_plan = forward_cop_plan(ankle_x, n) - stride * tau
    detrended_plan = cop_plan if cop_offset_m is None else cop_plan + cop_offset_m
    omega2 = GRAVITY_M_S2 / float(np.mean(com[np.arange(n, 2 * n), 2]))
    target = inverted_pendulum_com(detrended_plan, omega2, T) + stride * tau
    # invert com_x(φ) (monotonic) at the targets, over three cycles to handle the wrap
    com_x = com[:, 0] - shift
    phases = np.arange(3 * n) / n - 1.0
    warped = np.interp(target, com_x, phases)
    spectrum = np.fft.rfft(warped - tau)
    spectrum[WARP_HARMONICS + 1:] = 0.0
    return tau + np.fft.irfft(spectrum, n=n), cop_plan, omega2


def sideways_pendulum_shift(q: np.ndarray, params, warped: np.ndarray, omega2: float, T: float) -> np.ndarray:
    """How far (n,) m to move the pelvis sideways so that the CoM follows the inverted pendulum over the stance
    foot: the COP plan sits under the stance ankle's mean y in single support and moves to the other's in double
    support (a centimetre or two of sideways foot slip, which the truth carries)."""
    from gaitcli.kinematics.forward import forward_kinematics

    states = forward_kinematics(q, params)
    mass = np.asarray(params.mass_kg)
    com_y = np.einsum("b,nb->n", mass, states.com_m[:, :, 1]) / mass.sum()
    ankle_y = {s: states.joint_centre_m[:, JOINTS.index(f"ankle_{s}"), 1] for s in HEEL_STRIKE_PHASE}
    own = {s: np.mod(warped - off, 1.0) for s, off in HEEL_STRIKE_PHASE.items()}
    plan_y = np.zeros(warped.size)
    for side in HEEL_STRIKE_PHASE:
        other = "l" if side == "r" else "r"
        single = (own[side] >= DOUBLE_SUPPORT) & (own[side] < 0.5)
        plan_y[single] = np.mean(ankle_y[side][single])
        trailing = (own[side] >= 0.5) & (own[side] < STANCE_END)
        u = (own[side][trailing] - 0.5) / DOUBLE_SUPPORT
        plan_y[trailing] = np.mean(ankle_y[side][single]) * (1 - u) + np.mean(ankle_y[other][
            (own[other] >= DOUBLE_SUPPORT) & (own[other] < 0.5)]) * u
    return inverted_pendulum_com(plan_y, omega2, T) - com_y


def low_pass_pelvis(pelvis: np.ndarray, tau: np.ndarray, stride: float) -> np.ndarray:
    """The pelvis path (n, 3) m kept to its first ``PELVIS_HARMONICS`` (x, y, z) about the forward trend."""
    trend = np.outer(tau, [stride, 0.0, 0.0])
    spectrum = np.fft.rfft(pelvis - trend, axis=0)
    for axis, keep in enumerate(PELVIS_HARMONICS):
        spectrum[keep + 1:, axis] = 0.0
    return np.fft.irfft(spectrum, n=tau.size, axis=0) + trend


def cycle_events(warped: np.ndarray, tau: np.ndarray) -> list:
    """(phase 0..1, side, kind) of the cycle's heel strikes and toe offs: where the warped phase reaches the
    designed instants (right strike 0, left toe off ``DOUBLE_SUPPORT``, left strike 0.5, right toe off)."""
    unwrapped = np.concatenate([warped - 1, warped, warped + 1])
    taus = np.concatenate([tau - 1, tau, tau + 1])
    events = []
    for at, side, kind in ((0.0, "r", "heel_strike"), (DOUBLE_SUPPORT, "l", "toe_off"),
                           (0.5, "l", "heel_strike"), (0.5 + DOUBLE_SUPPORT, "r", "toe_off")):
        events.append((float(np.mod(np.interp(at, unwrapped, taus), 1.0)), side, kind))
    return events


def balanced_gait(geometry: Geometry, condition: Condition, params, *, iterations: int = 4,
                  samples: int | None = None) -> GaitDesign:
    """:func:`design_gait` over ``samples`` per cycle (default the period at ``ANALOG_RATE_HZ``), re-timed until
    the whole-body COP follows the planned heel → toe path.

    The pendulum model ignores the segments' angular momentum; each pass measures
    how far the true COP (from :func:`ground_reactions`) runs ahead of the plan and
    shifts the plan the other way.
    """
    design = design_gait(geometry, condition, params, samples=samples)
    offset = np.zeros(design.q.shape[0])
    for _ in range(iterations):
        _, _, _, _, cop, plan = ground_reactions(design, params, with_plan=True)
        offset -= cop[:, 0] - plan
        design = design_gait(geometry, condition, params, samples=samples, cop_offset_m=offset)
    return design


