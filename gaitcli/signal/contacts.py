"""Foot contacts on force plates: when each plate was loaded, and by which foot.

Positions are in model axes (x forward, y left, z up), metres; times in seconds
from the first marker frame; frames are 0-based indices into the marker arrays.

1. :func:`plate_contacts` finds the runs of *unfiltered* vertical force above the
   threshold at the analog rate (the zero-lag filter would spread the loading edge
   and move the crossing earlier by 1-2 frames), drops spikes shorter than
   ``min_run_s`` (a real plate's noise, which bridged would open a contact before
   the heel strike or span the whole trial: docs/plates_real.md), bridges dips
   shorter than ``min_gap_s``, drops runs shorter than ``min_contact_s``,
   and times each edge by linear interpolation of F_z across the threshold.
2. :func:`assign_contacts` gives each contact to the foot whose heel-toe segment is
   closest (horizontally) to the contact's COP path, using the frames with at
   least 10 % of the contact's peak vertical force. A contact is flagged instead of
   assigned when the COP strays from the chosen foot (median distance above
   ``max_distance_m``: two feet loaded the plate; ``'ambiguous'`` if the other foot
   was not seen), when the COP stays with each foot alone (within ``max_distance_m``
   of it and farther from the other) for ``min_alone_s`` or longer: two feet loaded
   the plate one after the other, however short the second's part (a foot stepping
   onto the far end of a plate the other foot's forefoot still loads), or when the
   two feet's mean distances differ by less than ``min_margin_m`` (``'ambiguous'``).
   Only COP inside the plate's outline counts (a COP jump outside it is noise). It also records
   whether the heel marker was over the plate at the onset and the toe marker at the
   offset, so that a foot landing half off a plate does not give a late heel strike.
3. :func:`plate_owner` tells which foot loads each plate in each frame, for
   :func:`~gaitcli.signal.forceplates.combine_loads`; :func:`partly_off` finds a foot standing partly off its
   plates, :func:`other_foot_over` the other foot resting over a loaded plate low enough to touch it,
   :func:`not_wholly_on` the stances Nexus's Plug-in Gait would leave without force.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gaitcli.core.events import SIDES
from gaitcli.core.numerics import true_runs
from gaitcli.errors import InputError, shown
from gaitcli.signal.forceplates import PlateLoad

__all__ = ["Contact", "plate_contacts", "assign_contacts", "plate_owner", "partly_off", "other_foot_over",
           "not_wholly_on", "outline_depth"]


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
    A ``'both_feet'`` contact (one foot stepping off a plate the other foot steps on)
    names in ``first_side`` the foot nearest its COP at the onset and in ``last_side``
    the one nearest at the end: the plate's onset is the first's heel strike, its end
    the last's toe off, and :func:`plate_owner` gives each its frames alone on the plate.
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
    first_side: str = ""
    last_side: str = ""

    @property
    def shared(self) -> bool:
        """Both feet stood on it and the feet at its ends are known: it is split (:func:`plate_owner`)."""
        return self.flag == "both_feet" and bool(self.first_side and self.last_side)


def plate_contacts(loads: list[PlateLoad], *, threshold_N: float, min_contact_s: float = 0.1,
                   min_gap_s: float = 0.05, min_run_s: float = 0.01) -> list[Contact]:
    """Contact intervals of every plate from its unfiltered vertical force (see module docstring).

    Parameters
    ----------
    loads : list of PlateLoad
        The plates; each one's ``raw_vertical_force_N`` at ``raw_rate_hz`` where present, else its
        (masked, filtered) ``force_N[:, 2]``.
    threshold_N : float
        Vertical force above which a plate is loaded, N.
    min_contact_s, min_gap_s, min_run_s : float
        Runs above the threshold shorter than ``min_run_s`` are noise and dropped; the rest, separated by
        less than ``min_gap_s``, are joined; runs shorter than ``min_contact_s`` are dropped. Seconds.

    Returns
    -------
    list of Contact
        Ordered by plate, then time; ``side`` not yet assigned.
    """
    if not (np.isfinite(threshold_N) and threshold_N >= 0):
        raise InputError(None, "threshold_N", f"got {shown(threshold_N)} (expected a force >= 0 N)")
    contacts = []
    for p, load in enumerate(loads):
        if load.raw_vertical_force_N is not None:
            fz, rate = np.asarray(load.raw_vertical_force_N, dtype=float), float(load.raw_rate_hz)
        else:
            fz, rate = load.force_N[:, 2], load.rate_hz
        fz = np.nan_to_num(fz, nan=0.0)
        starts, stops = true_runs(fz > threshold_N)
        lasting = (stops - starts) >= min_run_s * rate
        starts, stops = starts[lasting], stops[lasting]
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
                    edge_tolerance_m: float = 0.02, min_alone_s: float = 0.05) -> list[Contact]:
    """Give each contact to the foot whose heel-toe segment is closest to its COP path (see module docstring).

    Parameters
    ----------
    contacts : list of Contact
        From :func:`plate_contacts`.
    loads : list of PlateLoad
        The plates at the marker frames.
    heel_r, toe_r, heel_l, toe_l : array_like
        Foot markers (frames, 3), model axes, m; NaN allowed.
    max_distance_m : float
        A COP path further than this from the chosen foot (median) strays from it.
    min_margin_m : float
        The two feet's mean distances must differ by this much, else the contact is ambiguous.
    edge_tolerance_m : float
        Widens the plate outline for the heel and toe checks (markers sit a little behind the heel and
        above the toes); where a marker is not seen, or the plate has no outline, the plate is trusted.
    min_alone_s : float
        How long the COP must stay with each foot alone for a plate to count as loaded by both: longer
        than a COP jump that survives the 6 Hz filter, shorter than the end of a heel's load on a
        plate's far end.

    Returns
    -------
    list of Contact
        New contacts with ``side``, the distances, ``margin_m``, ``flag``, ``heel_inside``,
        ``toe_inside`` (and for two feet ``first_side``, ``last_side``) filled; a flagged contact has
        ``side = ''``.
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
        per_frame = {side: _segment_distance(cop, heel[frames[use], :2], toe[frames[use], :2])
                     for side, (heel, toe) in feet.items()}
        distances = {side: d[np.isfinite(d)] for side, d in per_frame.items()}
        mean = {s: float(d.mean()) if d.size else np.nan for s, d in distances.items()}
        stood_alone = _stood_alone(per_frame, cop, load.corners_m, max_distance_m=max_distance_m,
                                   edge_tolerance_m=edge_tolerance_m, min_frames=min_alone_s * load.rate_hz)
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
            if (strays and other_near) or all(stood_alone.values()):
                flag = "both_feet"
            elif strays or (len(seen) == 2 and margin < min_margin_m):
                flag = "ambiguous"
            else:
                side = best
        heel_inside = toe_inside = True
        first_side = last_side = ""
        if flag == "both_feet":  # who stood on it alone at its ends: the nearer foot over its first and last tenth
            tenth = max(1, int(np.ceil(0.1 * cop.shape[0])))
            nearer = {}
            for end, rows in (("first", slice(0, tenth)), ("last", slice(-tenth, None))):
                d = {s_: np.nanmean(_segment_distance(cop[rows], feet[s_][0][frames[use]][rows, :2],
                                                      feet[s_][1][frames[use]][rows, :2])) for s_ in SIDES}
                nearer[end] = min(SIDES, key=lambda s_: d[s_] if np.isfinite(d[s_]) else np.inf)
            first_side, last_side = nearer["first"], nearer["last"]
        if (side or first_side) and load.corners_m is not None:
            heel_inside = _inside(feet[side or first_side][0][c.first_frame, :2], load.corners_m, edge_tolerance_m)
            toe_inside = _inside(feet[side or last_side][1][c.last_frame, :2], load.corners_m, edge_tolerance_m)
        out.append(replace(c, side=side, distance_r_m=mean["r"], distance_l_m=mean["l"], margin_m=margin,
                           flag=flag, heel_inside=heel_inside, toe_inside=toe_inside, first_side=first_side,
                           last_side=last_side))
    return out


def _stood_alone(per_frame: dict, cop: np.ndarray, corners, *, max_distance_m: float, edge_tolerance_m: float,
                 min_frames: float) -> dict[str, bool]:
    """side → whether the COP stayed with that foot alone (within ``max_distance_m`` of it, farther from the
    other) for ``min_frames`` consecutive loaded frames, counting only COP inside the plate's outline."""
    on_plate = np.ones(cop.shape[0], bool) if corners is None else \
        _inside_each(cop, corners, edge_tolerance_m) & np.all(np.isfinite(cop), axis=1)
    out = {}
    for side, other in (("r", "l"), ("l", "r")):
        with np.errstate(invalid="ignore"):
            alone = on_plate & (per_frame[side] <= max_distance_m) & (per_frame[other] > max_distance_m)
        starts, stops = true_runs(alone)
        out[side] = bool(starts.size) and bool(np.max(stops - starts) >= min_frames)
    return out


def plate_owner(contacts: list[Contact], loads: list[PlateLoad], events=None, *, reach_s: float = 0.1) -> np.ndarray:
    """Which foot (``'r'``, ``'l'``, ``''``) loads each plate in each frame, shape (n_plates, n_frames).

    Each assigned contact owns its frames, extended over the adjacent frames in which
    the (filtered) plate is still loaded, up to the neighbouring contact and by at most ``reach_s`` (how far the
    6 Hz filter spreads a loading edge; a noisy plate's filtered baseline can stay above the threshold for
    seconds and would give the foot the other foot's stance: docs/plates_real.md). A ``'both_feet'``
    contact is split by ``events`` (:class:`~gaitcli.core.events.Events`): its first foot
    owns it until the other foot's heel strike, its last foot from the first foot's toe
    off; in between both feet stand on it and no foot owns it (their loads are unknown).
    """
    n = loads[0].n_frames if loads else 0
    owner = np.full((len(loads), n), "", dtype="<U1")
    for p, load in enumerate(loads):
        mine = sorted((c for c in contacts if c.plate_index == p), key=lambda c: c.first_frame)
        starts, stops = true_runs(load.loaded)
        for i, c in enumerate(mine):
            shared = c.shared and events is not None
            if not (c.side or shared):
                continue
            lo, hi = c.first_frame, c.last_frame + 1
            run = np.flatnonzero((starts <= c.last_frame) & (stops > c.first_frame))
            if run.size:
                reach = int(round(reach_s * load.rate_hz))
                lo = min(lo, max(starts[run[0]], c.first_frame - reach))
                hi = max(hi, min(stops[run[-1]], c.last_frame + 1 + reach))
            if i > 0:
                lo = max(lo, mine[i - 1].last_frame + 1)
            if i + 1 < len(mine):
                hi = min(hi, mine[i + 1].first_frame)
            if not shared:
                owner[p, lo:hi] = c.side
                continue
            start, stop = shared_frames(c, events, load.rate_hz)
            owner[p, lo:start], owner[p, stop:hi] = c.first_side, c.last_side
    return owner


def shared_frames(contact: Contact, events, rate_hz: float) -> tuple[int, int]:
    """First and last+1 frame of a ``'both_feet'`` contact in which both feet stand on it: from the second foot's
    heel strike to the first foot's toe off inside the contact (the whole contact where they are not found)."""
    first, last = contact.first_side, contact.last_side
    other = last if last != first else ("l" if first == "r" else "r")
    lo_t, hi_t = contact.first_frame / rate_hz, contact.last_frame / rate_hz
    strikes = events.times(other, "heel_strike")
    offs = events.times(first, "toe_off")
    strikes = strikes[(strikes > lo_t) & (strikes < hi_t)]
    offs = offs[(offs > lo_t) & (offs < hi_t)]
    start = int(np.ceil(strikes[0] * rate_hz - 1e-9)) if strikes.size else contact.first_frame
    stop = int(np.floor(offs[-1] * rate_hz + 1e-9)) + 1 if offs.size else contact.last_frame + 1
    return start, max(start, stop)



#: a foot marker counts as on the ground within this height above its lowest level in the trial, m
GROUND_MARGIN_M = 0.02


def partly_off(owner: np.ndarray, loads: list[PlateLoad], foot_points: dict, stance: dict, *,
               edge_tolerance_m: float = 0.02) -> dict[str, np.ndarray]:
    """side → (n,) frames in which that foot owns a plate but stands partly off the plates it owns: one of its
    markers on the ground lies outside their outlines (widened by ``edge_tolerance_m``) during its ``stance``
    (n,), so they carry only part of that foot's load (the rest is on the floor, or on a plate given to the other
    foot).

    ``foot_points[side]`` = (heel markers, toe markers), each a list of (frames, 3) arrays. A toe marker is on
    the ground within :data:`GROUND_MARGIN_M` of its lowest height; a heel marker from the heel strike until it
    rises above that level again (heel off), including the first frames of the stance in which the heel pad is
    already down and the marker still comes down.
    """
    out = {}
    n = owner.shape[1]
    for side, (heels, toes) in foot_points.items():
        owns = np.any(owner == side, axis=0) & stance[side]
        off = np.zeros(n, bool)
        for p, is_heel in [(h, True) for h in heels] + [(t, False) for t in toes]:
            with np.errstate(invalid="ignore"):
                low = p[:, 2] <= np.nanmin(p[:, 2], initial=np.inf) + GROUND_MARGIN_M
            grounded = low & stance[side]
            if is_heel:
                for a, b in zip(*true_runs(stance[side])):
                    down = np.flatnonzero(low[a:b])
                    if down.size:  # from the strike to the end of the first stretch on the ground
                        ends = np.flatnonzero(np.diff(down) > 1)
                        grounded[a:a + (down[ends[0]] if ends.size else down[-1]) + 1] = True
            on_own = np.zeros(n, bool)  # over a plate this foot owns in that frame
            for k, load in enumerate(loads):
                if load.corners_m is not None:
                    on_own |= (owner[k] == side) & _inside_each(p[:, :2], load.corners_m, edge_tolerance_m)
            off |= grounded & ~on_own
        out[side] = owns & off
    return out


#: a foot marker over a plate can touch it within this height above its height standing on a plate, m: below the
#: 12-32 mm by which the swinging foot's markers pass over a loaded plate in the real walks of docs/plates_real.md
TOUCH_MARGIN_M = 0.01
#: a foot marker moving slower than this horizontally rests on what is under it (docs/plates_real.md's survey), m/s
RESTING_SPEED_M_S = 0.6


def other_foot_over(owner: np.ndarray, loads: list[PlateLoad], foot_points: dict, *, rate_hz: float,
                    margin_m: float = TOUCH_MARGIN_M,
                    max_speed_m_s: float = RESTING_SPEED_M_S) -> dict[str, np.ndarray]:
    """side → (n_plates, n) frames in which that foot rests over a loaded plate the other foot owns, low enough to
    touch it: one of its markers (``foot_points[side]``, a list of (n, 3) arrays at ``rate_hz``, m) inside the
    plate's outline, at most ``margin_m`` above that marker's standing height (its lowest height above the plates
    its foot owns, over the frames it owns them; for a foot that owns none, its lowest height above the lowest
    plate) and moving slower than ``max_speed_m_s`` horizontally. The plate may then carry part of both feet's
    loads; a light load hardly moves the COP, so :func:`assign_contacts` cannot see it. A swing passing over is
    not counted: its markers pass 2-4 mm above their standing height in the synthetic walk (whose plates carry
    one foot) and 12-32 mm in the real walks, at 1-4 m/s."""
    n = owner.shape[1]
    tops = [None if load.corners_m is None else float(np.mean(np.asarray(load.corners_m)[:, 2])) for load in loads]
    lowest = min((t for t in tops if t is not None), default=0.0)
    out = {}
    for side, points in foot_points.items():
        other = "l" if side == "r" else "r"
        over = np.zeros((len(loads), n), bool)
        for p in points:
            p = np.asarray(p, dtype=float)
            heights = [p[owner[k] == side, 2] - tops[k] for k in range(len(loads)) if tops[k] is not None]
            heights = np.concatenate(heights) if heights else np.empty(0)
            heights = heights[np.isfinite(heights)]
            standing = heights.min() if heights.size else np.nanmin(p[:, 2], initial=np.inf) - lowest
            speed = np.linalg.norm(np.gradient(p[:, :2], axis=0), axis=1) * rate_hz if n > 1 else np.zeros(n)
            for k, load in enumerate(loads):
                if tops[k] is None or not np.isfinite(standing):
                    continue
                with np.errstate(invalid="ignore"):
                    low = (p[:, 2] - tops[k] <= standing + margin_m) & (speed <= max_speed_m_s)
                over[k] |= (owner[k] == other) & load.loaded & low & _inside_each(p[:, :2], load.corners_m, 0.0) \
                    & np.all(np.isfinite(p), axis=1)
        out[side] = over
    return out


def not_wholly_on(owner: np.ndarray, loads: list[PlateLoad], foot_points: dict, stance: dict, *,
                  radius_m: float) -> dict[str, np.ndarray]:
    """side → (n_plates, n) frames of that foot's ``stance`` in which it owns the plate but does not lie wholly on
    it: one of its markers (``foot_points[side]``: heel, toe, ankle, (n, 3) arrays, m), a ball of ``radius_m``
    (half the marker diameter), is not wholly inside the plate's outline. Nexus's Plug-in Gait gives a foot a
    plate only where it lies wholly on it (a toe over a step's edge included); gaitcli keeps such loads
    where :func:`partly_off` finds no marker on the ground off the plate."""
    n = owner.shape[1]
    out = {}
    for side, points in foot_points.items():
        outside = np.zeros((len(loads), n), bool)
        for k, load in enumerate(loads):
            if load.corners_m is None:
                continue
            mine = (owner[k] == side) & stance[side]
            for p in points:
                p = np.asarray(p, dtype=float)
                seen = np.all(np.isfinite(p), axis=1)
                outside[k] |= mine & seen & ~_inside_each(p[:, :2], load.corners_m, -radius_m)
        out[side] = outside
    return out


def _inside_each(points: np.ndarray, corners: np.ndarray, tolerance_m: float) -> np.ndarray:
    """Whether each 2-D point (n, 2) lies inside the convex outline ``corners`` (4, 2+) widened by
    ``tolerance_m``; rows with NaN count as inside (the plate is trusted)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    with np.errstate(invalid="ignore"):
        return (outline_depth(points, corners) >= -tolerance_m) | ~np.all(np.isfinite(points), axis=1)


def outline_depth(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """How far each 2-D point (n, 2+) lies inside the convex outline ``corners`` (4, 2+), m: its distance to the
    nearest edge, negative outside (NaN for NaN points)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))[:, :2]
    c = np.asarray(corners, dtype=float)[:, :2]
    edges = np.roll(c, -1, axis=0) - c
    area2 = np.sum(c[:, 0] * np.roll(c[:, 1], -1) - np.roll(c[:, 0], -1) * c[:, 1])
    cross = edges[None, :, 0] * (points[:, None, 1] - c[None, :, 1]) - edges[None, :, 1] * (points[:, None, 0]
                                                                                             - c[None, :, 0])
    return np.min(np.sign(area2) * cross / np.linalg.norm(edges, axis=1), axis=1)


def _segment_distance(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance of each 2-D point to the segment from ``a`` to ``b`` (row by row)."""
    ab = b - a
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.clip(np.einsum("ij,ij->i", points - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(points - (a + u[:, None] * ab), axis=1)


def _inside(point: np.ndarray, corners: np.ndarray, tolerance_m: float) -> bool:
    """Whether one 2-D point lies inside the outline (:func:`_inside_each`)."""
    return bool(_inside_each(np.asarray(point, dtype=float)[None, :2], corners, tolerance_m)[0])
