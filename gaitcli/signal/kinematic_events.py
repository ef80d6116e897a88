"""Heel strikes and toe offs from foot-marker kinematics (Zeni, Richards & Higginson 2008).

The coordinate-based method of Zeni et al. (2008, Gait & Posture 27:710-714),
used wherever a foot is not on a force plate. Positions are in model axes
(x forward, y left, z up), metres; times in seconds from the first marker frame.
"""

from __future__ import annotations

import numpy as np

from gaitcli.core.events import SIDES, Events
from gaitcli.core.numerics import true_runs
from gaitcli.core.validate import one_of
from gaitcli.errors import InputError

__all__ = ["kinematic_events"]

#: no event within this long of either end of a marker's (or the pelvis's) trajectory, s
EDGE_MARGIN_S = 0.1
#: the pelvis centre moving faster than this from one frame to the next has jumped (a marker lost or found), m/s
PELVIS_JUMP_M_S = 8.0


def kinematic_events(heel, toe, pelvis_centre, rate_hz: float, side: str, *, refine: bool = False,
                     min_prominence_m: float = 0.05, min_interval_s: float = 0.4,
                     min_speed_m_s: float = 0.1) -> Events:
    """Heel strikes and toe offs of one foot from its markers (Zeni et al. 2008).

    Heel strike: a maximum of the heel's horizontal position relative to the pelvis
    centre along the walking direction; toe off: a minimum of the toe's. The walking
    direction is the pelvis's horizontal displacement over ±0.5 s (less within 0.5 s of the ends of its
    trajectory, which a jump faster than :data:`PELVIS_JUMP_M_S` also ends; no event within
    :data:`EDGE_MARGIN_S` of them), so walking towards −x or along a curve works as well. Each time is refined
    to a fraction of a frame by a parabola through the three samples around the peak.

    The method finds the instant the foot's forward speed equals the pelvis's, which
    is before the true heel strike (the heel is still decelerating) and after the
    true toe off (the toe is accelerating).

    Parameters
    ----------
    heel, toe, pelvis_centre : array_like
        Trajectories (frames, 3), model axes, m.
    rate_hz : float
        Marker rate, Hz.
    side : str
        ``'r'`` or ``'l'``, the side the events are given.
    refine : bool
        Move each heel strike to where the heel stops descending: the first upward zero crossing of
        the heel marker's vertical velocity from 0.02 s before to 0.1 s after the Zeni time (none:
        the Zeni time stays). Toe offs are not refined: the toe marker sits on a metatarsal head,
        which rises well before the toes leave the ground (docs/decisions.md).
    min_prominence_m : float
        Prominence a peak needs, m.
    min_interval_s : float
        Least time between two events of one kind, s.
    min_speed_m_s : float
        Frames where the pelvis is slower than this give no events, m/s.

    Returns
    -------
    Events
        Source ``kinematics``.
    """
    one_of(side, SIDES, where="side")
    heel, toe, pelvis = (np.asarray(a, dtype=float) for a in (heel, toe, pelvis_centre))
    n = pelvis.shape[0]
    if heel.shape != (n, 3) or toe.shape != (n, 3) or pelvis.shape != (n, 3):
        raise InputError(None, "markers", f"got heel {heel.shape}, toe {toe.shape}, pelvis {pelvis.shape} "
                                          "(expected three (frames, 3) arrays)")
    # a pelvis marker appearing or disappearing moves the centre of those seen at once: the trajectory is cut
    # there, as at a gap
    speed = np.linalg.norm(np.diff(pelvis[:, :2], axis=0), axis=1) * rate_hz
    with np.errstate(invalid="ignore"):
        pelvis = np.where(np.concatenate([[False], speed > PELVIS_JUMP_M_S])[:, None], np.nan, pelvis)
    half = max(1, int(round(0.5 * rate_hz)))
    idx = np.arange(n)
    first, last = np.zeros(n, int), np.full(n, n - 1)  # the pelvis's finite run around each frame
    for a, b in zip(*true_runs(np.isfinite(pelvis[:, :2]).all(axis=1))):
        first[a:b], last[a:b] = a, b - 1
    ahead, behind = np.minimum(idx + half, last), np.maximum(idx - half, first)  # ±0.5 s, less at a run's ends
    step = pelvis[ahead, :2] - pelvis[behind, :2]
    length = np.linalg.norm(step, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = step / length[:, None]
        slow = ~(length / ((ahead - behind) / rate_hz) >= min_speed_m_s)
    direction[slow] = np.nan
    heel_rel = np.einsum("ij,ij->i", heel[:, :2] - pelvis[:, :2], direction)
    toe_rel = np.einsum("ij,ij->i", toe[:, :2] - pelvis[:, :2], direction)
    distance = max(1, int(round(min_interval_s * rate_hz)))
    margin = max(1, int(round(EDGE_MARGIN_S * rate_hz)))
    strikes = _peak_times(heel_rel, distance, min_prominence_m, margin) / rate_hz
    offs = _peak_times(-toe_rel, distance, min_prominence_m, margin) / rate_hz
    if refine:
        strikes = _heel_landing(strikes, heel[:, 2], rate_hz, window_s=(-0.02, 0.1))
    return Events.concatenate([
        Events.from_times(strikes, rate_hz=rate_hz, side=side, kind="heel_strike", source="kinematics"),
        Events.from_times(offs, rate_hz=rate_hz, side=side, kind="toe_off", source="kinematics"),
    ])


def _peak_times(y: np.ndarray, distance: int, prominence: float, margin: int = 1) -> np.ndarray:
    """Sub-frame positions (in frames) of the maxima of ``y``, found in each finite run separately, at least
    ``margin`` frames inside it (a marker's last frames before a gap are its least reliable)."""
    times = []
    for a, b in zip(*true_runs(np.isfinite(y))):
        seg = y[a:b]
        if seg.size < 3:
            continue
        from scipy.signal import find_peaks  # here, not at import: scipy.signal is slow to import

        peaks, _ = find_peaks(seg, distance=distance, prominence=prominence)
        peaks = peaks[(peaks >= margin) & (peaks < seg.size - margin)]
        if peaks.size == 0:
            continue
        y0, y1, y2 = seg[peaks - 1], seg[peaks], seg[peaks + 1]
        curvature = y0 - 2 * y1 + y2
        with np.errstate(invalid="ignore", divide="ignore"):
            delta = np.where(curvature < 0, 0.5 * (y0 - y2) / curvature, 0.0)
        times.append(a + peaks + np.clip(delta, -0.5, 0.5))
    return np.concatenate(times) if times else np.zeros(0)


def _heel_landing(times_s: np.ndarray, height_m: np.ndarray, rate_hz: float, *, window_s: tuple) -> np.ndarray:
    """Move each heel strike to the first step from descending to not descending inside ``t + window_s``.

    Vertical velocities are forward differences placed half-way between frames; the
    zero crossing is interpolated linearly. Events without a crossing are kept.
    """
    velocity = np.diff(height_m) * rate_hz
    out = times_s.copy()
    for i, t in enumerate(times_s):
        lo = max(int(np.floor((t + window_s[0]) * rate_hz)), 0)
        hi = min(int(np.ceil((t + window_s[1]) * rate_hz)), len(velocity) - 1)
        v = velocity[lo:hi + 1]
        k = np.flatnonzero((v[:-1] < 0) & (v[1:] >= 0))
        if k.size:
            j = k[0]
            out[i] = (lo + j + 0.5 + v[j] / (v[j] - v[j + 1])) / rate_hz
    return out
