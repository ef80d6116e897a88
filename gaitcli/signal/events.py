"""Gait events (heel strike, toe off) from plate loading and from foot-marker kinematics.

Where a foot lands on a force plate, its heel strike and toe off are the
threshold crossings of the plate's vertical force (:mod:`gaitcli.signal.contacts`);
everywhere else they come from the markers (:mod:`gaitcli.signal.kinematic_events`).
All positions are in model axes (x forward, y left, z up), metres; times in
seconds from the first marker frame; frames are 0-based indices into the marker
arrays.

:func:`detect_events` merges a foot's overlapping contacts on several plates
(a foot straddling two plates), takes the heel strike from the earliest onset if
the heel was over that plate and the toe off from the latest offset if the toe
was over that plate, and fills in kinematic events for the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.events import KINDS, SIDES, Events
from gaitcli.errors import InputError
from gaitcli.signal.contacts import Contact, assign_contacts, plate_contacts, plate_owner
from gaitcli.signal.forceplates import PlateLoad
from gaitcli.signal.kinematic_events import kinematic_events

__all__ = ["EventDetection", "detect_events", "Contact", "kinematic_events"]


@dataclass
class EventDetection:
    """Result of :func:`detect_events`: the events, the plate contacts with their foot, and
    ``owner`` (n_plates, n_frames) of ``'r'``/``'l'``/``''`` for :func:`~gaitcli.signal.forceplates.combine_loads`."""

    events: Events
    contacts: list[Contact]
    owner: np.ndarray


def detect_events(loads: list[PlateLoad], feet: dict, pelvis_centre, rate_hz: float, threshold_N: float, *,
                  duplicate_s: float = 0.1, refine: bool = False, min_contact_s: float = 0.1,
                  max_distance_m: float = 0.1, min_margin_m: float = 0.05) -> EventDetection:
    """Heel strikes and toe offs of both feet: from plates where a foot was on one, else from kinematics.

    Parameters
    ----------
    loads : list of PlateLoad
        The plates at the marker rate (may be empty).
    feet : dict
        ``'r'`` and ``'l'`` → ``(heel, toe)`` marker trajectories (frames, 3), model axes, m.
    pelvis_centre : array_like
        (frames, 3), m: the walking direction of :func:`kinematic_events`.
    rate_hz : float
        Marker rate, Hz.
    threshold_N : float
        Vertical force above which a plate is loaded, N.
    duplicate_s : float
        A kinematic event this close to a plate event of the same side and kind is dropped, s.
    refine : bool
        Passed to :func:`kinematic_events`.
    min_contact_s : float
        Passed to :func:`plate_contacts`.
    max_distance_m, min_margin_m : float
        Passed to :func:`assign_contacts`.

    Returns
    -------
    EventDetection
        The events, the assigned contacts and the per-frame plate owner.
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
        plate_ev = Events.concatenate([
            _plate_events([c for c in contacts if c.side == side and not c.flag], rate_hz, side),
            _shared_plate_events([c for c in contacts if c.shared], rate_hz, side)])
        kin = kinematic_events(feet[side][0], feet[side][1], pelvis_centre, rate_hz, side, refine=refine)
        keep = np.ones(len(kin), dtype=bool)
        for kind in KINDS:
            plate_t = plate_ev.of(kind=kind).time_s
            is_kind = kin.kind == kind
            if plate_t.size:
                near = np.abs(kin.time_s[:, None] - plate_t[None, :]).min(axis=1) < duplicate_s
                keep &= ~(is_kind & near)
        parts += [plate_ev, kin.select(keep)]
    events = Events.concatenate(parts)
    return EventDetection(events, contacts, plate_owner(contacts, loads, events))


def _shared_plate_events(contacts: list[Contact], rate_hz: float, side: str) -> Events:
    """A plate two feet stood on times only its ends: the first foot's heel strike and the last foot's toe off."""
    strikes = [c.on_time_s for c in contacts if c.first_side == side and c.heel_inside and np.isfinite(c.on_time_s)]
    offs = [c.off_time_s for c in contacts if c.last_side == side and c.toe_inside and np.isfinite(c.off_time_s)]
    return Events.concatenate([
        Events.from_times(strikes, rate_hz=rate_hz, side=side, kind="heel_strike", source="plate"),
        Events.from_times(offs, rate_hz=rate_hz, side=side, kind="toe_off", source="plate")])


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
