"""Gait events (heel strike, toe off) from plate loading and from foot-marker kinematics.

Where a foot lands on a force plate, its heel strike and toe off are the
threshold crossings of the plate's vertical force; everywhere else they come
from the markers by the coordinate-based method of Zeni, Richards & Higginson
(2008, Gait & Posture 27:710-714). All positions are in model axes (x forward,
y left, z up), metres; times in seconds from the first marker frame; frames are
0-based indices into the marker arrays.

Plate contacts:

1. :func:`plate_contacts` finds the runs of *unfiltered* vertical force above the
   threshold at the analog rate (the zero-lag filter would spread the loading edge
   and move the crossing earlier by 1-2 frames), bridges dips shorter than
   ``min_gap_s``, drops runs shorter than ``min_contact_s``, and times each edge by
   linear interpolation of F_z across the threshold.
2. :func:`assign_contacts` gives each contact to the foot whose heel-toe segment is
   closest (horizontally) to the contact's COP path, using the frames with at
   least 10 % of the contact's peak vertical force. A contact is flagged instead of
   assigned when the COP strays from the chosen foot (90th percentile of the
   distance above ``max_distance_m``: two feet loaded the plate; ``'ambiguous'``
   if the other foot was not seen) or when the two feet's mean distances differ by
   less than ``min_margin_m`` (``'ambiguous'``). It also records
   whether the heel marker was over the plate at the onset and the toe marker at the
   offset, so that a foot landing half off a plate does not give a late heel strike.
3. :func:`detect_events` merges a foot's overlapping contacts on several plates
   (a foot straddling two plates), takes the heel strike from the earliest onset if
   the heel was over that plate and the toe off from the latest offset if the toe
   was over that plate, and fills in kinematic events for the rest.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.signal import find_peaks

from gaitcli.core.events import KINDS, SIDES, Events
from gaitcli.errors import InputError
from gaitcli.signal.butterworth import finite_runs
from gaitcli.signal.forceplates import PlateLoad

__all__ = ["Contact", "EventDetection", "plate_contacts", "assign_contacts", "plate_owner",
           "kinematic_events", "detect_events"]


@dataclass(frozen=True)
class Contact:
    """One loading of one plate: frames ``first_frame..last_frame`` (inclusive) at the marker rate.

    ``on_time_s``/``off_time_s``: threshold crossings of the raw vertical force (NaN
    where the plate was already loaded at the start or still loaded at the end).
    Filled by :func:`assign_contacts`: ``side`` (``'r'``, ``'l'`` or ``''``), the mean
    horizontal COP-to-foot distances, ``margin_m`` (their difference), ``flag``
    (``''``, ``'both_feet'``, ``'ambiguous'``, ``'no_markers'`` or ``'no_cop'``: the
    filtered load never passed the threshold), and whether the
    heel marker was over the plate at the onset and the toe marker at the offset.
    """

    plate_index: int
    plate_name: str
    first_frame: int
    last_frame: int
    on_time_s: float
    off_time_s: float
    side: str = ""
    distance_r_m: float = np.nan
    distance_l_m: float = np.nan
    margin_m: float = np.nan
    flag: str = ""
    heel_inside: bool = True
    toe_inside: bool = True


@dataclass
class EventDetection:
    """Result of :func:`detect_events`: the events, the plate contacts with their foot, and
    ``owner`` (n_plates, n_frames) of ``'r'``/``'l'``/``''`` for :func:`~gaitcli.signal.forceplates.combine_loads`."""

    events: Events
    contacts: list[Contact]
    owner: np.ndarray


def plate_contacts(loads: list[PlateLoad], *, threshold_N: float, min_contact_s: float = 0.1,
                   min_gap_s: float = 0.05) -> list[Contact]:
    """Contact intervals of every plate from its unfiltered vertical force (see module docstring).

    Uses ``raw_vertical_force_N`` at ``raw_rate_hz`` where present, else the (masked,
    filtered) ``force_N[:, 2]``. Runs above ``threshold_N`` separated by less than
    ``min_gap_s`` are joined; runs shorter than ``min_contact_s`` are dropped. Ordered
    by plate, then time.
    """
    if not (np.isfinite(threshold_N) and threshold_N >= 0):
        raise InputError(None, "threshold_N", f"got {threshold_N!r} (expected a force >= 0 N)")
    contacts = []
    for p, load in enumerate(loads):
        if load.raw_vertical_force_N is not None:
            fz, rate = np.asarray(load.raw_vertical_force_N, dtype=float), float(load.raw_rate_hz)
        else:
            fz, rate = load.force_N[:, 2], load.rate_hz
        fz = np.nan_to_num(fz, nan=0.0)
        starts, stops = finite_runs(fz > threshold_N)
        if len(starts) > 1:
            keep = np.concatenate([[True], (starts[1:] - stops[:-1]) >= min_gap_s * rate])
            starts, stops = starts[keep], stops[np.concatenate([keep[1:], [True]])]
        long_enough = (stops - starts) >= min_contact_s * rate
        last_t = (load.n_frames - 1) / load.rate_hz
        for a, b in zip(starts[long_enough], stops[long_enough]):
            on = np.nan if a == 0 else (a - 1 + (threshold_N - fz[a - 1]) / (fz[a] - fz[a - 1])) / rate
            off = np.nan if b == len(fz) else (b - 1 + (fz[b - 1] - threshold_N) / (fz[b - 1] - fz[b])) / rate
            on = np.nan if on > last_t else on
            off = np.nan if off > last_t else off
            first = 0 if np.isnan(on) else int(np.ceil(on * load.rate_hz - 1e-9))
            last = load.n_frames - 1 if np.isnan(off) else int(np.floor(off * load.rate_hz + 1e-9))
            if a / rate > last_t or last < first:
                continue
            contacts.append(Contact(p, load.name, first, min(last, load.n_frames - 1), float(on), float(off)))
    return contacts


def assign_contacts(contacts: list[Contact], loads: list[PlateLoad], heel_r, toe_r, heel_l, toe_l, *,
                    max_distance_m: float = 0.1, min_margin_m: float = 0.05,
                    edge_tolerance_m: float = 0.02) -> list[Contact]:
    """Give each contact to the foot whose heel-toe segment is closest to its COP path (see module docstring).

    Foot markers are (frames, 3) in model axes, NaN allowed. Returns new
    :class:`Contact` objects with ``side``, distances, ``margin_m``, ``flag``,
    ``heel_inside`` and ``toe_inside`` filled; a flagged contact has ``side = ''``.
    ``edge_tolerance_m`` widens the plate outline for the heel/toe check (markers sit
    a little behind the heel and above the toes); where the marker is not seen, or
    the plate has no outline, the plate is trusted.
    """
    feet = {"r": (np.asarray(heel_r, float), np.asarray(toe_r, float)),
            "l": (np.asarray(heel_l, float), np.asarray(toe_l, float))}
    out = []
    for c in contacts:
        load = loads[c.plate_index]
        frames = np.arange(c.first_frame, c.last_frame + 1)
        fz = load.force_N[frames, 2]
        use = load.loaded[frames] & (fz >= 0.1 * fz.max(initial=0.0))
        cop = load.cop_m[frames[use], :2]
        distances = {}
        for side, (heel, toe) in feet.items():
            d = _segment_distance(cop, heel[frames[use], :2], toe[frames[use], :2])
            distances[side] = d[np.isfinite(d)]
        mean = {s: float(d.mean()) if d.size else np.nan for s, d in distances.items()}
        seen = [s for s in SIDES if np.isfinite(mean[s])]
        side, flag, margin = "", "", np.nan
        if not use.any():
            flag = "no_cop"
        elif not seen:
            flag = "no_markers"
        else:
            best = min(seen, key=lambda s: mean[s])
            if len(seen) == 2:
                margin = abs(mean["r"] - mean["l"])
            strays = np.median(distances[best]) > max_distance_m
            other = [s for s in seen if s != best]
            # a COP that strays from the best foot points at two feet only if the other foot comes near it too
            other_near = bool(other) and np.percentile(distances[other[0]], 10) <= max_distance_m
            if strays and other_near:
                flag = "both_feet"
            elif strays or (len(seen) == 2 and margin < min_margin_m):
                flag = "ambiguous"
            else:
                side = best
        heel_inside = toe_inside = True
        if side and load.corners_m is not None:
            heel, toe = feet[side]
            heel_inside = _inside(heel[c.first_frame, :2], load.corners_m, edge_tolerance_m)
            toe_inside = _inside(toe[c.last_frame, :2], load.corners_m, edge_tolerance_m)
        out.append(replace(c, side=side, distance_r_m=mean["r"], distance_l_m=mean["l"], margin_m=margin,
                           flag=flag, heel_inside=heel_inside, toe_inside=toe_inside))
    return out


def plate_owner(contacts: list[Contact], loads: list[PlateLoad]) -> np.ndarray:
    """Which foot (``'r'``, ``'l'``, ``''``) loads each plate in each frame, shape (n_plates, n_frames).

    Each assigned contact owns its frames, extended over the adjacent frames in which
    the (filtered) plate is still loaded, up to the neighbouring contact.
    """
    n = loads[0].n_frames if loads else 0
    owner = np.full((len(loads), n), "", dtype="<U1")
    for p, load in enumerate(loads):
        mine = sorted((c for c in contacts if c.plate_index == p), key=lambda c: c.first_frame)
        starts, stops = finite_runs(load.loaded)
        for i, c in enumerate(mine):
            if not c.side:
                continue
            lo, hi = c.first_frame, c.last_frame + 1
            run = np.flatnonzero((starts <= c.last_frame) & (stops > c.first_frame))
            if run.size:
                lo, hi = min(lo, starts[run[0]]), max(hi, stops[run[-1]])
            if i > 0:
                lo = max(lo, mine[i - 1].last_frame + 1)
            if i + 1 < len(mine):
                hi = min(hi, mine[i + 1].first_frame)
            owner[p, lo:hi] = c.side
    return owner


def kinematic_events(heel, toe, pelvis_centre, rate_hz: float, side: str, *, refine: bool = False,
                     min_prominence_m: float = 0.05, min_interval_s: float = 0.4,
                     min_speed_m_s: float = 0.1) -> Events:
    """Heel strikes and toe offs of one foot from its markers (Zeni et al. 2008).

    Heel strike: a maximum of the heel's horizontal position relative to the pelvis
    centre along the walking direction; toe off: a minimum of the toe's. The walking
    direction is the pelvis's horizontal displacement over +-0.5 s (frames where the
    pelvis moves slower than ``min_speed_m_s`` give no events), so walking towards -x
    or along a curve works as well. Peaks need a prominence of ``min_prominence_m``
    and ``min_interval_s`` between events of one kind; their time is refined to a
    fraction of a frame by a parabola through the three samples around the peak.

    The method finds the instant the foot's forward speed equals the pelvis's, which
    is before the true heel strike (the heel is still decelerating) and after the
    true toe off (the toe is accelerating). With ``refine=True`` each heel strike is
    moved to where the heel stops descending: the first upward zero crossing of the
    heel marker's vertical velocity from 0.02 s before to 0.1 s after the Zeni time
    (linear interpolation; no crossing keeps the Zeni time). Toe offs are not
    refined: the toe marker sits on a metatarsal head, which rises during push-off
    well before the toes leave the ground (on walking2.c3d the same rule put toe off
    80 ms before the plate's, while the Zeni toe off was 15 ms after it).
    """
    if side not in SIDES:
        raise InputError(None, "side", f"got {side!r} (expected one of {list(SIDES)})")
    heel, toe, pelvis = (np.asarray(a, dtype=float) for a in (heel, toe, pelvis_centre))
    n = pelvis.shape[0]
    if heel.shape != (n, 3) or toe.shape != (n, 3) or pelvis.shape != (n, 3):
        raise InputError(None, "markers", f"got heel {heel.shape}, toe {toe.shape}, pelvis {pelvis.shape} "
                                          "(expected three (frames, 3) arrays)")
    half = max(1, int(round(0.5 * rate_hz)))
    idx = np.arange(n)
    ahead, behind = np.minimum(idx + half, n - 1), np.maximum(idx - half, 0)
    step = pelvis[ahead, :2] - pelvis[behind, :2]
    length = np.linalg.norm(step, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = step / length[:, None]
        slow = ~(length / ((ahead - behind) / rate_hz) >= min_speed_m_s)
    direction[slow] = np.nan
    heel_rel = np.einsum("ij,ij->i", heel[:, :2] - pelvis[:, :2], direction)
    toe_rel = np.einsum("ij,ij->i", toe[:, :2] - pelvis[:, :2], direction)
    distance = max(1, int(round(min_interval_s * rate_hz)))
    strikes = _peak_times(heel_rel, distance, min_prominence_m) / rate_hz
    offs = _peak_times(-toe_rel, distance, min_prominence_m) / rate_hz
    if refine:
        strikes = _heel_landing(strikes, heel[:, 2], rate_hz, window_s=(-0.02, 0.1))
    return Events.concatenate([
        Events.from_times(strikes, rate_hz=rate_hz, side=side, kind="heel_strike", source="kinematics"),
        Events.from_times(offs, rate_hz=rate_hz, side=side, kind="toe_off", source="kinematics"),
    ])


def detect_events(loads: list[PlateLoad], feet: dict, pelvis_centre, rate_hz: float, threshold_N: float, *,
                  duplicate_s: float = 0.1, refine: bool = False, min_contact_s: float = 0.1,
                  max_distance_m: float = 0.1, min_margin_m: float = 0.05) -> EventDetection:
    """Heel strikes and toe offs of both feet: from plates where a foot was on one, else from kinematics.

    ``feet`` maps ``'r'`` and ``'l'`` to ``(heel, toe)`` marker trajectories (frames, 3);
    ``loads`` are the plates at the marker rate ``rate_hz`` (may be empty). Kinematic
    events within ``duplicate_s`` of a plate event of the same side and kind are
    dropped. ``refine`` is passed to :func:`kinematic_events`; ``min_contact_s`` to
    :func:`plate_contacts`; ``max_distance_m`` and ``min_margin_m`` to
    :func:`assign_contacts`. Returns the events, the assigned contacts and the
    per-frame plate owner.
    """
    missing = [s for s in SIDES if s not in feet]
    if missing:
        raise InputError(None, "feet", f"got no markers for side(s) {missing} (expected 'r' and 'l')")
    for load in loads:
        if abs(load.rate_hz - rate_hz) > 1e-9 * rate_hz:
            raise InputError(None, "rate_hz", f"plate {load.name} is at {load.rate_hz:g} Hz "
                                              f"(expected the marker rate {rate_hz:g} Hz)")
    contacts = plate_contacts(loads, threshold_N=threshold_N, min_contact_s=min_contact_s)
    contacts = assign_contacts(contacts, loads, feet["r"][0], feet["r"][1], feet["l"][0], feet["l"][1],
                               max_distance_m=max_distance_m, min_margin_m=min_margin_m)
    parts = []
    for side in SIDES:
        plate_ev = _plate_events([c for c in contacts if c.side == side and not c.flag], rate_hz, side)
        kin = kinematic_events(feet[side][0], feet[side][1], pelvis_centre, rate_hz, side, refine=refine)
        keep = np.ones(len(kin), dtype=bool)
        for kind in KINDS:
            plate_t = plate_ev.of(kind=kind).time_s
            is_kind = kin.kind == kind
            if plate_t.size:
                near = np.abs(kin.time_s[:, None] - plate_t[None, :]).min(axis=1) < duplicate_s
                keep &= ~(is_kind & near)
        parts += [plate_ev, kin.select(keep)]
    return EventDetection(Events.concatenate(parts), contacts, plate_owner(contacts, loads))


def _plate_events(contacts: list[Contact], rate_hz: float, side: str) -> Events:
    """Heel strike and toe off of each group of a foot's time-overlapping contacts (a foot on several plates)."""
    contacts = sorted(contacts, key=lambda c: c.first_frame)
    groups: list[list[Contact]] = []
    for c in contacts:
        if groups and c.first_frame <= max(g.last_frame for g in groups[-1]) + 1:
            groups[-1].append(c)
        else:
            groups.append([c])
    strikes, offs = [], []
    for g in groups:
        on = np.array([c.on_time_s for c in g])
        off = np.array([c.off_time_s for c in g])
        if not np.isnan(on).any() and g[int(np.argmin(on))].heel_inside:
            strikes.append(on.min())
        if not np.isnan(off).any() and g[int(np.argmax(off))].toe_inside:
            offs.append(off.max())
    return Events.concatenate([
        Events.from_times(strikes, rate_hz=rate_hz, side=side, kind="heel_strike", source="plate"),
        Events.from_times(offs, rate_hz=rate_hz, side=side, kind="toe_off", source="plate"),
    ])


def _peak_times(y: np.ndarray, distance: int, prominence: float) -> np.ndarray:
    """Sub-frame positions (in frames) of the maxima of ``y``, found in each finite run separately."""
    times = []
    for a, b in zip(*finite_runs(np.isfinite(y))):
        seg = y[a:b]
        if seg.size < 3:
            continue
        peaks, _ = find_peaks(seg, distance=distance, prominence=prominence)
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


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of each 2-D point to the segment from ``a`` to ``b`` (row by row)."""
    ab = b - a
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(points - (a + u[:, None] * ab), axis=1)


def _inside(point: np.ndarray, corners: np.ndarray, tolerance_m: float) -> bool:
    """Whether a 2-D point lies inside the convex outline ``corners`` (4, 2+) widened by ``tolerance_m``.

    A point with NaN coordinates counts as inside (the plate is trusted).
    """
    if not np.all(np.isfinite(point)):
        return True
    c = np.asarray(corners, dtype=float)[:, :2]
    edges = np.roll(c, -1, axis=0) - c
    area2 = np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])
    cross = edges[:, 0] * (point[1] - c[:, 1]) - edges[:, 1] * (point[0] - c[:, 0])
    signed = np.sign(area2) * cross / np.linalg.norm(edges, axis=1)
    return bool(np.all(signed >= -tolerance_m))
