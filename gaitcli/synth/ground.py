"""Ground reactions consistent with a designed gait, split between the two feet.

The whole-body wrench the ground must supply for zero pelvis residual,
``F = Σ m (a + g)`` (N) and ``M = Σ (r × m (a + g) + dL/dt)`` (N·m, about the
origin), goes to the stance foot in single support and is shared between the
feet in double support along the line joining their centres of pressure, so
both feet's loads start and end at zero continuously.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.kinematics.model import JOINTS

if TYPE_CHECKING:
    from gaitcli.synth.gait import GaitDesign

HEEL_COP_M = -0.04  # where the COP starts at heel strike, forward of the ankle centre


def periodic_derivatives(y, period_s):
    """First and second time derivatives of samples of a periodic signal over one period (spectral)."""
    n = y.shape[0]
    k = np.fft.rfftfreq(n, d=period_s / n) * 2 * np.pi
    Y = np.fft.rfft(y, axis=0)
    shape = (-1,) + (1,) * (y.ndim - 1)
    d1 = np.fft.irfft(Y * (1j * k).reshape(shape), n=n, axis=0)
    d2 = np.fft.irfft(Y * (-(k ** 2)).reshape(shape), n=n, axis=0)
    return d1, d2


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


def ground_reactions(design: GaitDesign, params, *, gravity_m_s2: float = GRAVITY_M_S2, with_plan: bool = False):
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
