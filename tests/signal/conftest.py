"""A walking-like synthetic trial with known events and known ground-reaction loads.

The pelvis moves forward at constant speed. Each foot is a rigid heel-toe pair:
still on the ground during stance, and in swing it moves forward by one stride
with a half-cosine horizontal profile (zero speed at toe off and heel strike)
and a half-sine vertical arc. The ground load of a stance is two point loads,
under the heel and under the forefoot, whose shares shift from heel to forefoot
during stance, so the centre of pressure slides from heel to toe. A plate feels
every point load inside its outline, so plates placed anywhere give the right
partial, straddled or two-feet loads without special cases.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate

HEEL_TO_TOE_M = 0.18  # heel marker to toe marker
HEEL_POINT_M = 0.02  # heel load point, ahead of the heel marker
FORE_POINT_M = 0.17  # forefoot load point, ahead of the heel marker
FOOT_Y_M = {"r": -0.09, "l": 0.09}
MARKER_Z_M = 0.03
SWING_HEIGHT_M = 0.08


@dataclass
class Walk:
    """Synthetic trial: markers at ``rate_hz``, plates at ``analog_rate_hz``, and the truth."""

    rate_hz: float
    analog_rate_hz: float
    time_s: np.ndarray
    pelvis: np.ndarray
    feet: dict
    plates: list
    heel_strikes: dict
    toe_offs: dict
    speed_m_s: float
    stride_s: float
    stance_s: float
    stride_m: float
    body_weight_N: float
    first_strike_s: dict
    plate_stances: list = field(default_factory=list)  # per plate: set of (side, k) that load it
    foot_force_N: dict = field(default_factory=dict)  # per side, (analog samples, 3), all stances
    foot_cop_m: dict = field(default_factory=dict)
    foot_free_moment_Nm: dict = field(default_factory=dict)

    def stance_heel_x(self, side: str, k: int) -> float:
        return _stance_heel_x(self, side, k)


def _stance_heel_x(w, side, k):
    t_hs = w.first_strike_s[side] + k * w.stride_s
    return w.speed_m_s * (t_hs + w.stance_s / 2) - HEEL_TO_TOE_M / 2


def _foot(w, side, t):
    """Heel and toe (len(t), 3) of one foot at times ``t``."""
    k = np.floor((t - w.first_strike_s[side]) / w.stride_s)
    phase = (t - w.first_strike_s[side]) / w.stride_s - k
    x0 = _stance_heel_x(w, side, k)
    swing = phase >= w.stance_s / w.stride_s
    s = np.where(swing, (phase - w.stance_s / w.stride_s) / (1 - w.stance_s / w.stride_s), 0.0)
    heel = np.empty((len(t), 3))
    heel[:, 0] = x0 + np.where(swing, w.stride_m * (1 - np.cos(np.pi * s)) / 2, 0.0)
    heel[:, 1] = FOOT_Y_M[side]
    heel[:, 2] = MARKER_Z_M + np.where(swing, SWING_HEIGHT_M * np.sin(np.pi * s), 0.0)
    toe = heel.copy()
    toe[:, 0] += HEEL_TO_TOE_M
    return heel, toe


def _stance_load(w, side, s):
    """Total force (n, 3), heel/forefoot shares, free moment (n,) at stance fraction ``s`` in [0, 1]."""
    bw = w.body_weight_N
    sign = 1.0 if side == "r" else -1.0
    force = np.stack([-0.18 * bw * np.sin(2 * np.pi * s),
                      sign * 0.05 * bw * np.sin(np.pi * s),
                      1.15 * bw * (np.sin(np.pi * s) + 0.35 * np.sin(3 * np.pi * s))], axis=1)
    u = np.clip((s - 0.1) / 0.6, 0.0, 1.0)
    fore = u * u * (3 - 2 * u)
    free = sign * 4.0 * np.sin(2 * np.pi * s)
    return force, 1.0 - fore, fore, free


def make_walk(*, plates=(), duration_s=4.0, rate_hz=100.0, analog_rate_hz=1000.0, speed_m_s=1.2,
              stride_s=1.1, stance_fraction=0.6, first_strike_s=None, body_weight_N=700.0,
              noise_N=1.5, noise_Nm=0.3, seed=0) -> Walk:
    """Build a synthetic walk. ``plates``: (side, k, dx_m, length_m, width_m) — a plate centred
    ``dx_m`` ahead of the middle of stance ``k`` of that foot, on the walkway centre line."""
    first = {"r": 0.3, "l": 0.85} if first_strike_s is None else dict(first_strike_s)
    n = int(round(duration_s * rate_hz))
    t = np.arange(n) / rate_hz
    w = Walk(rate_hz=rate_hz, analog_rate_hz=analog_rate_hz, time_s=t, pelvis=None, feet={}, plates=[],
             heel_strikes={}, toe_offs={}, speed_m_s=speed_m_s, stride_s=stride_s,
             stance_s=stance_fraction * stride_s, stride_m=speed_m_s * stride_s, body_weight_N=body_weight_N,
             first_strike_s=first)
    w.pelvis = np.stack([speed_m_s * t, np.zeros(n), 0.95 + 0.02 * np.cos(4 * np.pi * t / stride_s)], axis=1)
    for side in ("r", "l"):
        w.feet[side] = _foot(w, side, t)
        ks = np.arange(-3, int(duration_s / stride_s) + 3)
        hs = first[side] + ks * stride_s
        w.heel_strikes[side] = hs[(hs >= 0) & (hs <= t[-1])]
        to = hs + w.stance_s
        w.toe_offs[side] = to[(to >= 0) & (to <= t[-1])]

    m = int(round(duration_s * analog_rate_hz))
    ta = np.arange(m) / analog_rate_hz
    parts = []  # (side, k, point (3,), force (m,3), free (m,))
    for side in ("r", "l"):
        total_f = np.zeros((m, 3))
        total_moment = np.zeros((m, 3))
        for k in range(-3, int(duration_s / stride_s) + 3):
            t_hs = first[side] + k * stride_s
            s = (ta - t_hs) / w.stance_s
            on = (s >= 0) & (s <= 1)
            if not on.any():
                continue
            force, heel_share, fore_share, free = _stance_load(w, side, np.clip(s, 0, 1))
            force[~on] = 0
            free = np.where(on, free, 0.0)
            x0 = _stance_heel_x(w, side, k)
            for share, dx in ((heel_share, HEEL_POINT_M), (fore_share, FORE_POINT_M)):
                point = np.array([x0 + dx, FOOT_Y_M[side], 0.0])
                f_part = force * share[:, None]
                parts.append((side, k, point, f_part, free * share))
                total_f += f_part
                total_moment += np.cross(point, f_part)
                total_moment[:, 2] += free * share
        w.foot_force_N[side] = total_f
        with np.errstate(divide="ignore", invalid="ignore"):
            cop = np.stack([-total_moment[:, 1] / total_f[:, 2], total_moment[:, 0] / total_f[:, 2],
                            np.zeros(m)], axis=1)
        w.foot_cop_m[side] = cop
        w.foot_free_moment_Nm[side] = total_moment[:, 2] - (cop[:, 0] * total_f[:, 1] - cop[:, 1] * total_f[:, 0])

    rng = np.random.default_rng(seed)
    for i, (side, k, dx, length, width) in enumerate(plates):
        cx = _stance_heel_x(w, side, k) + HEEL_TO_TOE_M / 2 + dx
        centre = np.array([cx, 0.0, 0.0])
        corners = centre + np.array([[length / 2, width / 2, 0], [-length / 2, width / 2, 0],
                                     [-length / 2, -width / 2, 0], [length / 2, -width / 2, 0]])
        force = np.zeros((m, 3))
        moment = np.zeros((m, 3))
        stances = set()
        for p_side, p_k, point, f_part, free in parts:
            if abs(point[0] - cx) <= length / 2 and abs(point[1]) <= width / 2 and np.any(f_part[:, 2] > 0):
                force += f_part
                moment += np.cross(point - centre, f_part)
                moment[:, 2] += free
                stances.add((p_side, p_k))
        force += rng.normal(0, noise_N, force.shape)
        moment += rng.normal(0, noise_Nm, moment.shape)
        w.plates.append(ForcePlate(f"FP{i + 1}", force, moment, centre, corners, analog_rate_hz))
        w.plate_stances.append(stances)
    return w


# ------------------------------------------------- shared by the event tests

EVENT_RATE_HZ = 100.0
EVENT_THRESHOLD_N = 20.0
CENTRED_PLATE = (0.0, 0.6, 0.4)  # dx, length, width: a plate centred under the foot


def walk_loads(walk):
    """The walk's plates filtered and resampled to the marker rate, as the event functions take them."""
    from gaitcli.signal.forceplates import plate_load

    return [plate_load(p, cutoff_hz=6.0, threshold_N=EVENT_THRESHOLD_N, rate_hz=EVENT_RATE_HZ) for p in walk.plates]


def true_event_times(walk, side, kind):
    """The walk's true heel strike or toe off times (s) of one side."""
    return (walk.heel_strikes if kind == "heel_strike" else walk.toe_offs)[side]


def event_errors_frames(events, walk, side, kind):
    """Frames from each found event of ``side``/``kind`` to the nearest true one."""
    truth = true_event_times(walk, side, kind)
    found = events.of(side, kind).time_s
    return np.array([(t - truth[np.argmin(np.abs(truth - t))]) * EVENT_RATE_HZ for t in found])


@pytest.fixture
def walk_factory():
    """The synthetic walk generator :func:`make_walk`."""
    return make_walk
