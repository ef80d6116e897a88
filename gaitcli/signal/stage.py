"""The ``filter`` stage: gap filling, zero-lag filtering, plate loads, events (3.1.4).

A pure function from a :class:`~gaitcli.core.recording.Recording` (markers and plates
in model axes, landmark names already mapped) to a :class:`FilterResult`. The gait events are
the trial file's own where it has any (``events: auto``; ``file`` insists, ``detect`` ignores
them), else detected; the plate contacts are found and given to a foot either way.
"""

from __future__ import annotations

import dataclasses
import warnings
from dataclasses import dataclass

import numpy as np

from gaitcli.core.container import FootLoad, Trial, load_known_frames
from gaitcli.core.events import SIDE_NAMES, SIDES, Events
from gaitcli.core.numerics import frame_spans
from gaitcli.core.recording import Markers, Recording
from gaitcli.core.validate import number, parameter
from gaitcli.errors import GaitWarning, InputError
from gaitcli.signal.butterworth import design_frequency_hz, design_sos, edge_frames, lowpass
from gaitcli.signal.contacts import (
    not_wholly_on,
    other_foot_over,
    outline_depth,
    partly_off,
    plate_owner,
    shared_frames,
)
from gaitcli.signal.cycles import strides, walking_events
from gaitcli.signal.events import Contact, EventDetection, detect_events, kinematic_events
from gaitcli.signal.forceplates import PlateLoad, combine_loads, plate_load, resample_to_frames, resting_offsets
from gaitcli.signal.gaps import Gap, fill_gaps

#: foot landmarks used for events and plate-to-foot assignment: heel, toe (first choice, fallback)
HEEL = {"r": ("CAr",), "l": ("CAl",)}
TOE = {"r": ("FMr", "VMr", "MT2r"), "l": ("FMl", "VMl", "MT2l")}
ANKLE = {"r": ("LMr",), "l": ("LMl",)}
PELVIS = ("ASISr", "ASISl", "PSISr", "PSISl")
#: the marker diameter where the file's PROCESSING:MarkerDiameter does not give one, m (Vicon's 14 mm markers)
DEFAULT_MARKER_DIAMETER_M = 0.014
#: a foot is near a plate (for its resting reading) with a marker over its outline widened by this, m, and at
#: most NEAR_HEIGHT_M above or below its top
NEAR_M, NEAR_HEIGHT_M = 0.1, 0.3
EVENT_CHOICES = ("auto", "file", "detect")
PLATE_FRAMES = ("auto", "sample", "mean")
#: what the filter's ``auto`` settings stand for: the dissertation's 6 Hz for markers and plates, the plates
#: sampled at the frames (3.1.4); in a Plug-in Gait session Vicon Nexus's plates (unfiltered, each frame the mean
#: of its samples) and 8 Hz markers, nearest Vicon's own kinetics and the synthetic truth (docs/decisions.md,
#: "Plug-in Gait sessions: Nexus's plates, 8 Hz markers")
AUTO_SETTINGS = {None: {"cutoff_hz": 6.0, "force_cutoff_hz": 6.0, "plate_frames": "sample"},
                 "plug_in_gait": {"cutoff_hz": 8.0, "force_cutoff_hz": 0.0, "plate_frames": "mean"}}
CUTOFF_EXPECTED = "a finite number of Hz ≥ 0 (0: no filtering), or auto"


def cutoff(value) -> float | str:
    """A cut-off as a pipeline file or the command line gives it: ``auto`` or a finite number of Hz ≥ 0."""
    if isinstance(value, str):
        if value.strip().lower() == "auto":
            return "auto"
        value = float(value)  # the command line's text; ValueError for other words
    try:
        return number(value, where=None, low=0.0)
    except InputError:
        raise ValueError(value) from None


@dataclass(frozen=True)
class FilterConfig:
    """Parameters of ``gait filter`` (3.1.4)."""

    cutoff_hz: float | str = parameter(
        "auto", parse=cutoff, expected=CUTOFF_EXPECTED, metavar="HZ|auto",
        help="Net cut-off of the zero-lag filter for markers, Hz (0: no filtering); auto: 6 Hz, 8 Hz in a Plug-in "
             "Gait session.")
    force_cutoff_hz: float | str = parameter(
        "auto", parse=cutoff, expected=CUTOFF_EXPECTED, metavar="HZ|auto",
        help="The same for the force-plate signals, before the COP is formed, Hz (0: no filtering); auto: 6 Hz, "
             "unfiltered in a Plug-in Gait session.")
    plate_frames: str = parameter(
        "auto", choices=PLATE_FRAMES,
        help="The plates' value at a marker frame: their sample at its time (sample) or the mean of the samples "
             "centred on it, as Vicon Nexus (mean); auto: mean in a Plug-in Gait session, else sample.")
    order: int = parameter(2, low=1, high=8, help="Butterworth order of one pass.")
    max_gap_frames: int = parameter(10, low=0, help="Longer marker gaps stay NaN.")
    force_threshold_N: float = parameter(20.0, low=0.0, low_open=True,
                                         help="COP and free moment only above this vertical load, N.")
    events: str = parameter("auto", choices=EVENT_CHOICES,
                            help="Gait events: the trial file's own (file: its C3D EVENT group), detected from "
                                 "plates and foot markers (detect), or the file's where it has any (auto).")


@dataclass
class FilterResult:
    """Filtered trial at the marker rate, plus the filtered plate signals at the analog rate.

    ``trial``: filtered markers, per-foot loads and events (what later stages use).
    """

    trial: Trial
    recording: Recording  # as read: raw markers, plates, lab axes, reader's notes
    gaps: list[Gap]
    plates: list[PlateLoad]  # filtered, at the marker rate
    plates_analog: list[PlateLoad]  # filtered, at the analog rate
    plate_loads_per_foot: dict[str, PlateLoad]  # per-foot sums of the plates each foot stood on
    plate_owner: np.ndarray  # (plates, frames) 'r', 'l' or ''
    contacts: list[Contact]
    design_cutoff_hz: float | None
    force_design_cutoff_hz: float | None
    config: FilterConfig

    @property
    def raw_markers(self) -> Markers:
        return self.recording.markers

    @property
    def markers(self) -> Markers:
        return self.trial.markers

    @property
    def events(self) -> Events:
        return self.trial.events


def _first_present(markers: Markers, names) -> np.ndarray | None:
    for name in names:
        if name in markers:
            return markers.get(name)
    return None


def pelvis_centre(markers: Markers) -> np.ndarray:
    """Mean of the available ASIS/PSIS markers per frame (or of all markers when none is there), m."""
    present = [markers.index(n) for n in PELVIS if n in markers]
    columns = markers.positions_m[:, present, :] if present else markers.positions_m
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN frames stay NaN
        return np.nanmean(columns, axis=1)


def _frames(load: PlateLoad, n: int) -> PlateLoad:
    """Trim or NaN-pad a resampled plate load to exactly the ``n`` marker frames."""
    def fit(x, fill):
        x = np.asarray(x)
        if x.shape[0] >= n:
            return x[:n]
        pad = np.full((n - x.shape[0],) + x.shape[1:], fill, dtype=x.dtype)
        return np.concatenate([x, pad])
    return dataclasses.replace(load, force_N=fit(load.force_N, 0.0), cop_m=fit(load.cop_m, np.nan),
                               free_moment_Nm=fit(load.free_moment_Nm, np.nan), loaded=fit(load.loaded, False))


def calibrate_kinematic_events(events: Events, feet: dict, pelvis: np.ndarray, rate_hz: float) -> Events:
    """Shift the kinematic (Zeni) events by their bias against the plate events of the same trial.

    Zeni's heel strike comes before the true one and its toe off after (the foot is
    still moving relative to the pelvis). Where a plate timed a heel strike or toe
    off, the Zeni event of the same contact (within ±0.2 s) gives the bias; the
    median bias per foot and kind (both feet's where a foot was never on a plate)
    is removed from that foot's kinematic events of the kind.
    Trials without plate events are left as they are.
    """
    if not feet or not len(events.of(source="plate")):
        return events
    zeni = Events.concatenate(kinematic_events(heel, toe, pelvis, rate_hz, side) for side, (heel, toe) in feet.items())
    shifted = events.time_s.copy()
    for kind in ("heel_strike", "toe_off"):
        bias = {}
        for side in feet:
            bias[side] = []
            for t in events.times(side, kind, "plate"):
                candidates = zeni.times(side, kind)
                near = candidates[np.abs(candidates - t) <= 0.2]
                if near.size:
                    bias[side].append(t - near[np.argmin(np.abs(near - t))])
        pooled = [b for values in bias.values() for b in values]
        for side in feet:
            own = bias[side] or pooled  # a foot's own bias where a plate saw it, else both feet's
            if own:
                mine = events.mask(side, kind, "kinematics")
                shifted[mine] += float(np.median(own))
    return Events(np.rint(shifted * rate_hz).astype(int), shifted, events.side, events.kind, events.source)


def filter_markers(markers: Markers, cfg: FilterConfig) -> tuple[Markers, list[Gap]]:
    """Fill gaps up to ``cfg.max_gap_frames`` by cubic interpolation, then filter (3.1.4)."""
    filled, gaps = fill_gaps(markers.positions_m, max_gap_frames=cfg.max_gap_frames)
    smooth = lowpass(filled, rate_hz=markers.rate_hz, cutoff_hz=cfg.cutoff_hz, order=cfg.order, axis=0) \
        if cfg.cutoff_hz else filled  # 0 turns the filter off (exact synthetic data)
    return Markers(markers.labels, smooth, markers.rate_hz, markers.first_frame), gaps


def with_session_defaults(cfg: FilterConfig, marker_set: str | None) -> FilterConfig:
    """``cfg`` with each ``auto`` replaced by what it stands for with ``marker_set`` (:data:`AUTO_SETTINGS`)."""
    auto = AUTO_SETTINGS.get(marker_set, AUTO_SETTINGS[None])
    return dataclasses.replace(cfg, **{k: v for k, v in auto.items() if getattr(cfg, k) == "auto"})


def check_cutoffs(cfg: FilterConfig, recording: Recording, path=None) -> None:
    """Cut-offs must lie below the Nyquist frequency of the signals they filter, and (unless 0: no filtering) at
    or above 1/duration of the recording: a slower filter has nothing to separate and an impulse response
    longer than the data (at 1e-9 Hz, 1e11 samples)."""
    rate = recording.markers.rate_hz
    lowest = rate / max(recording.markers.n_frames - 1, 1)
    for key, value in (("cutoff_hz", cfg.cutoff_hz), ("force_cutoff_hz", cfg.force_cutoff_hz)):
        if 0 < value < lowest:
            raise InputError(path, f"filter.{key}", f"got {value:g} Hz (expected at least 1/duration = {lowest:.3g} "
                                                    "Hz of the recording, or 0 for no filtering)")
    if cfg.cutoff_hz >= rate / 2:
        raise InputError(path, "filter.cutoff_hz", f"got {cfg.cutoff_hz:g} Hz (expected below the Nyquist frequency "
                                                   f"{rate / 2:g} Hz of its {rate:g} Hz markers)")
    if recording.plates and cfg.force_cutoff_hz >= rate / 2:  # plate signals end up at the marker frames
        raise InputError(path, "filter.force_cutoff_hz", f"got {cfg.force_cutoff_hz:g} Hz (expected below the "
                                                         f"Nyquist frequency {rate / 2:g} Hz of the marker frames)")


def foot_loads(plate_loads_per_foot: dict[str, PlateLoad], events: Events, time_s: np.ndarray) -> dict[str, FootLoad]:
    """Both feet's loads at the marker frames, with the frames in which each is known (in swing or on a plate)."""
    n = time_s.size
    out = {}
    for side in SIDES:
        load = plate_loads_per_foot.get(side)
        loaded = np.zeros(n, bool) if load is None else np.nan_to_num(load.force_N[:, 2]) > 0
        known = load_known_frames(events, time_s, loaded, side)
        out[side] = FootLoad.unmeasured(n, known) if load is None else FootLoad(
            np.asarray(load.force_N, float), np.asarray(load.cop_m, float), np.asarray(load.free_moment_Nm, float),
            known)
    return out


def without_partial_feet(owner: np.ndarray, plates: list[PlateLoad], markers: Markers, events: Events) -> np.ndarray:
    """``owner`` with no plate given to a foot in the frames in which it stands partly off the plates
    (:func:`~gaitcli.signal.contacts.partly_off`: its load there is more than the plates measured), warned."""
    if not plates:
        return owner
    points = {side: ([markers.get(n) for n in HEEL[side] if n in markers],
                     [markers.get(n) for n in TOE[side] if n in markers]) for side in SIDES}
    stance = {side: events.stance_mask(side, markers.time_s) for side in SIDES}
    off = partly_off(owner, plates, {s: p for s, p in points.items() if p[0] or p[1]}, stance)
    owner = owner.copy()
    for side, frames in off.items():
        if frames.any():
            names = [plates[k].name for k in range(len(plates)) if np.any((owner[k] == side) & frames)]
            owner[:, frames] = np.where(owner[:, frames] == side, "", owner[:, frames])
            warnings.warn(f"{', '.join(names)}: the {SIDE_NAMES[side]} foot stands partly off the plates in frames "
                          f"{frame_spans(np.flatnonzero(frames), markers.first_frame)} (a heel or toe marker on the "
                          "ground outside them): its load there is unknown", GaitWarning, stacklevel=3)
    return owner


def foot_markers(markers: Markers) -> dict[str, list[np.ndarray]]:
    """side → the foot's heel, toe and ankle markers present, (n, 3) m each (sides without any left out)."""
    out = {side: [markers.get(n) for n in HEEL[side] + TOE[side] + ANKLE[side] if n in markers] for side in SIDES}
    return {side: points for side, points in out.items() if points}


def without_other_foot(owner: np.ndarray, plates: list[PlateLoad],
                       markers: Markers) -> tuple[np.ndarray, np.ndarray]:
    """``owner`` with no plate given in the frames in which a foot rests over a loaded plate the other foot owns, low
    enough to touch it (:func:`~gaitcli.signal.contacts.other_foot_over`), and those frames (n,), in which both
    feet's loads are unknown; warned."""
    n = owner.shape[1]
    if not plates:
        return owner, np.zeros(n, bool)
    over = other_foot_over(owner, plates, foot_markers(markers), rate_hz=markers.rate_hz)
    owner, both = owner.copy(), np.zeros(n, bool)
    for side, frames in over.items():
        for k in np.flatnonzero(frames.any(axis=1)):
            other = "l" if side == "r" else "r"
            warnings.warn(f"{plates[k].name}: the {SIDE_NAMES[side]} foot rests over it, low enough to touch it, "
                          f"while it carries the {SIDE_NAMES[other]} foot's load in frames "
                          f"{frame_spans(np.flatnonzero(frames[k]), markers.first_frame)}: it may carry part of both "
                          "feet's loads, so both are unknown there", GaitWarning, stacklevel=3)
            both |= frames[k]
    owner[:, both] = ""
    return owner, both


def warn_not_wholly_on(owner: np.ndarray, plates: list[PlateLoad], markers: Markers, events: Events,
                       diameter_m: float) -> None:
    """Warn the stances in which gaitcli gives a foot a plate's load while the foot does not lie wholly on the plate
    (:func:`~gaitcli.signal.contacts.not_wholly_on`): Nexus's Plug-in Gait leaves such a stance without force."""
    points = foot_markers(markers)
    stance = {side: events.stance_mask(side, markers.time_s) for side in SIDES}
    for side, frames in not_wholly_on(owner, plates, points, stance, radius_m=diameter_m / 2).items():
        for k in np.flatnonzero(frames.any(axis=1)):
            mine = frames[k]
            beyond = max(float(np.nanmax(diameter_m / 2 - outline_depth(p[mine], plates[k].corners_m), initial=0.0))
                         for p in points[side])
            warnings.warn(f"{plates[k].name}: the {SIDE_NAMES[side]} foot does not lie wholly on it in frames "
                          f"{frame_spans(np.flatnonzero(mine), markers.first_frame)} (a marker's edge up to "
                          f"{1000 * beyond:.0f} mm beyond its outline), where gaitcli gives it the plate's load: "
                          "Nexus's Plug-in Gait, which gives a foot a plate only while it lies wholly on it, would "
                          "leave this stance without force", GaitWarning, stacklevel=3)


def warn_resting_offsets(recording: Recording, plates: list[PlateLoad], markers: Markers, cfg: FilterConfig) -> None:
    """Warn a plate that reads at least half the contact threshold for 0.1 s or longer while no foot is near it
    (a marker over its outline widened by :data:`NEAR_M`, within :data:`NEAR_HEIGHT_M` of its top): an offset or a
    drift of its zero, which the loads of the feet on it carry too."""
    n, rate = markers.n_frames, markers.rate_hz
    feet = foot_markers(markers)
    if len(feet) < 2:  # without both feet's markers no frame is known to be free of feet
        return
    points = [p for side_points in feet.values() for p in side_points]
    for raw, load in zip(recording.plates, plates):
        if load.corners_m is None:
            continue
        fz = np.nan_to_num(np.asarray(raw.force_N, float)[:, 2])
        # the plates' cut-off, or where they are not filtered the dissertation's, to average the noise out
        fz = lowpass(fz, rate_hz=raw.rate_hz, cutoff_hz=cfg.force_cutoff_hz or AUTO_SETTINGS[None]["force_cutoff_hz"])
        fz = resample_to_frames(fz, source_rate_hz=raw.rate_hz, rate_hz=rate)[:n]
        top = float(np.mean(load.corners_m[:, 2]))
        near = np.zeros(fz.size, bool)
        for p in points:
            p = p[:fz.size]
            with np.errstate(invalid="ignore"):
                near |= (np.abs(p[:, 2] - top) <= NEAR_HEIGHT_M) & (outline_depth(p, load.corners_m) >= -NEAR_M)
        runs = resting_offsets(fz, quiet=~near, rate_hz=rate, limit_N=cfg.force_threshold_N / 2)
        if runs:
            low, high = min(r[2] for r in runs), max(r[3] for r in runs)
            spans = ", ".join(f"{a + markers.first_frame}–{b + markers.first_frame}" for a, b, _, _ in runs)
            warnings.warn(f"{load.name}: reads {low:.0f} to {high:.0f} N with no foot near it in frames {spans}: an "
                          "offset or drift of its zero, which the load of a foot on it carries too", GaitWarning,
                          stacklevel=3)


def separated_plates(recording: Recording, plates: list[PlateLoad], contacts: list[Contact], events: Events,
                     cfg: FilterConfig) -> list[PlateLoad]:
    """The plates as the feet are given them: a plate both feet stood on is filtered again with its double support
    left out (NaN), so that the zero-lag filter does not carry one foot's load into the other's frames beside it
    (at 6 Hz the filter reaches about 110 ms; docs/decisions.md)."""
    rate, n = recording.markers.rate_hz, recording.markers.n_frames
    out = list(plates)
    for index in sorted({c.plate_index for c in contacts if c.shared}):
        raw = recording.plates[index]
        force, moment = np.array(raw.force_N, float), np.array(raw.moment_Nm, float)
        ratio = raw.rate_hz / rate
        for c in contacts:
            if c.plate_index == index and c.shared:
                start, stop = shared_frames(c, events, rate)
                # the analog samples strictly between the last frame of the first foot and the first of the last
                lo, hi = int(np.floor((start - 1) * ratio)) + 1, int(np.ceil(stop * ratio))
                force[lo:hi], moment[lo:hi] = np.nan, np.nan
        out[index] = _frames(plate_load(dataclasses.replace(raw, force_N=force, moment_Nm=moment),
                                        cutoff_hz=cfg.force_cutoff_hz, threshold_N=cfg.force_threshold_N,
                                        rate_hz=rate, frame_means=cfg.plate_frames == "mean"), n)
    return out


def use_file_events(recording: Recording, cfg: FilterConfig, path=None) -> bool:
    """Whether the filter takes the trial file's own gait events (``cfg.events``: file, or auto and the file has
    some) instead of detecting them; ``file`` without any is an :class:`InputError` naming the file and EVENT."""
    if cfg.events == "file" and not len(recording.events):
        where = path if path is not None else recording.source
        raise InputError(where, "EVENT", "no gait events in the file (expected Foot Strike/Foot Off events with a "
                                         "Left/Right context, or labels such as LHS, RTO; or filter.events: auto "
                                         "or detect)")
    return cfg.events != "detect" and len(recording.events) > 0


#: how many set-aside strides a message names (the rest counted)
STRIDES_NAMED = 2


def checked_walking_events(events: Events, first_frame: int, rate_hz: float, path, from_file: bool) -> Events:
    """``events`` without the strides that cannot be walking (:func:`~gaitcli.signal.cycles.walking_events`),
    warned with their reasons; an InputError where fewer strides of the file's own events can be walking than
    cannot (a damaged EVENT group; detected events are only warned)."""
    kept, set_aside = walking_events(events)
    if not set_aside:
        return events
    source = "the trial file's EVENT group" if from_file else "the detected events"

    def frame(t: float) -> int:
        return int(round(t * rate_hz)) + first_frame

    named = "; ".join(f"{SIDE_NAMES[side]} {frame(a)}–{frame(b)}: {why}"
                      for side, a, b, why in set_aside[:STRIDES_NAMED])
    more = f" and {len(set_aside) - STRIDES_NAMED} more" if len(set_aside) > STRIDES_NAMED else ""
    usable = [st for st in strides(kept) if np.isfinite(st.toe_off_s)]
    if from_file and len(usable) < len(set_aside):  # a few strides of random events can look like walking
        raise InputError(path, "EVENT",
                         f"{len(set_aside)} strides cannot be walking, {len(usable)} can (frames {named}{more}; "
                         "expected heel strike, toe off and heel strike of each foot in order, a stance of 40–80 %)")
    warnings.warn(f"{len(set_aside)} strides of {source} set aside, their events unused: they cannot be walking "
                  f"(frames {named}{more})", GaitWarning, stacklevel=3)
    return kept


def filter_trial(recording: Recording, cfg: FilterConfig, *, marker_set: str | None = None,
                 path=None) -> FilterResult:
    """Run the filter stage on a recording whose labels are model landmarks where mapped.

    ``marker_set`` (the subject's) sets what ``auto`` settings stand for (:func:`with_session_defaults`); the
    result's ``config`` holds what was used. ``path`` names the trial file in error messages.
    """
    cfg = with_session_defaults(cfg, marker_set)
    check_cutoffs(cfg, recording, path)
    markers, gaps = filter_markers(recording.markers, cfg)
    long_gaps = [g for g in gaps if not g.filled]
    if long_gaps:
        listing = ", ".join(f"{markers.labels[g.marker_index]} frames {g.first_frame + markers.first_frame}–"
                            f"{g.last_frame + markers.first_frame}" for g in long_gaps[:6])
        more = f" and {len(long_gaps) - 6} more" if len(long_gaps) > 6 else ""
        warnings.warn(f"{len(long_gaps)} marker gap(s) longer than {cfg.max_gap_frames} frames left unfilled "
                      f"(the segments they track are NaN there): {listing}{more}", GaitWarning, stacklevel=2)

    rate = markers.rate_hz
    n = markers.n_frames
    plates_analog = [plate_load(p, cutoff_hz=cfg.force_cutoff_hz, threshold_N=cfg.force_threshold_N)
                     for p in recording.plates]
    plates = [_frames(plate_load(p, cutoff_hz=cfg.force_cutoff_hz, threshold_N=cfg.force_threshold_N, rate_hz=rate,
                                 frame_means=cfg.plate_frames == "mean"),
                      n) for p in recording.plates]

    feet = {}
    for side in ("r", "l"):
        heel = _first_present(markers, HEEL[side])
        toe = _first_present(markers, TOE[side])
        if heel is not None and toe is not None:
            feet[side] = (heel, toe)
    from_file = use_file_events(recording, cfg, path)
    if len(feet) < 2:
        warnings.warn("no heel (CAr/CAl) and toe (FMr/FMl, VMr/VMl or MT2r/MT2l) landmarks for both feet: "
                      + ("no plate-to-foot assignment" if from_file else "no gait events and no plate-to-foot "
                         "assignment") + " (add a marker_map naming them)", GaitWarning, stacklevel=2)
        detection = EventDetection(Events(), [], np.full((len(plates), n), "", dtype="<U1"))
    else:
        detection = detect_events(plates, feet, pelvis_centre(markers), rate_hz=rate,
                                  threshold_N=cfg.force_threshold_N, refine=False,
                                  duplicate_s=0.35)  # one foot cannot strike twice within 0.35 s
    events = recording.events if from_file else \
        calibrate_kinematic_events(detection.events, feet, pelvis_centre(markers), rate)
    events = checked_walking_events(events, markers.first_frame, rate, path, from_file)
    # a plate two feet stood on is split at the (calibrated) events of the foot stepping on and the one stepping off
    owner = plate_owner(detection.contacts, plates, events) if plates else detection.owner
    owner = without_partial_feet(owner, plates, markers, events)
    owner, both_unknown = without_other_foot(owner, plates, markers)
    diameter = float(recording.subject_metadata.get("PROCESSING:MarkerDiameter",
                                                    1000 * DEFAULT_MARKER_DIAMETER_M)) / 1000
    warn_not_wholly_on(owner, plates, markers, events, diameter)
    warn_resting_offsets(recording, plates, markers, cfg)
    detection = dataclasses.replace(detection, events=events, owner=owner)
    for c in detection.contacts:
        if c.shared:
            start, stop = shared_frames(c, events, rate)
            first, last = (SIDE_NAMES[x] for x in (c.first_side, c.last_side))
            warnings.warn(f"{c.plate_name}: both feet on it in frames {start + markers.first_frame}–"
                          f"{stop - 1 + markers.first_frame} ({start / rate:.2f}–{(stop - 1) / rate:.2f} s): no foot "
                          "is given its load there (the loads of both are unknown)" + ("" if from_file else
                          f"; the plate times only the {first} heel strike and the {last} toe off, the steps in "
                          "between are timed from the foot markers"), GaitWarning, stacklevel=2)
        elif c.flag:
            warnings.warn(f"{c.plate_name}: contact at {c.on_time_s:.2f}–{c.off_time_s:.2f} s not assigned to a foot "
                          f"({c.flag.replace('_', ' ')}); its load is left out of the per-foot ground reactions",
                          GaitWarning, stacklevel=2)
    per_foot = combine_loads(separated_plates(recording, plates, detection.contacts, events, cfg), detection.owner) \
        if plates else {}
    force_design = design_frequency_hz(cfg.force_cutoff_hz, recording.plates[0].rate_hz, order=cfg.order) \
        if recording.plates and cfg.force_cutoff_hz else None
    design = design_frequency_hz(cfg.cutoff_hz, rate, order=cfg.order) if cfg.cutoff_hz else None
    history = (f"read {recording.source}" if recording.source else "read",
               f"markers: gaps up to {cfg.max_gap_frames} frames filled by cubic interpolation, "
               + (f"order-{cfg.order} Butterworth forward and backward at {design:.3f} Hz "
                  f"(net cut-off {cfg.cutoff_hz:g} Hz)" if design else "not filtered"),
               f"plates: {len(plates)}, "
               + (f"filtered at net {cfg.force_cutoff_hz:g} Hz" if cfg.force_cutoff_hz else "not filtered")
               + (", each frame the mean of its samples" if cfg.plate_frames == "mean" else "") + ", COP above "
               f"{cfg.force_threshold_N:g} N; events from "
               + ("the trial file's EVENT group" if from_file else "plates and foot markers"))
    feet_loads = foot_loads(per_foot, detection.events, markers.time_s)
    unknown = both_unknown.copy()
    for plate in plates:
        bad = ~np.isfinite(plate.force_N).all(axis=1)
        if bad.any():
            unknown |= bad
            warnings.warn(f"{plate.name}: {int(bad.sum())} frames whose channels are not numbers (NaN): its force is "
                          "NaN there, and both feet's loads count as unknown (their joint moments are flagged)",
                          GaitWarning, stacklevel=2)
    if unknown.any():
        feet_loads = {side: dataclasses.replace(load, known=load.known & ~unknown) for side, load in feet_loads.items()}
    trial = Trial(markers=markers, feet=feet_loads,
                  events=detection.events, history=history,
                  source="" if recording.source is None else str(recording.source),
                  lab_to_model=np.asarray(recording.lab_to_model, float),
                  subject_metadata=dict(recording.subject_metadata),
                  marker_labels=dict(recording.marker_labels),
                  filter_edge_frames=edge_frames(design_sos(cfg.cutoff_hz, rate, order=cfg.order)) if cfg.cutoff_hz
                  else 0)
    return FilterResult(trial=trial, recording=recording, gaps=gaps, plates=plates,
                        plates_analog=plates_analog, plate_loads_per_foot=per_foot, plate_owner=detection.owner,
                        contacts=detection.contacts, design_cutoff_hz=design,
                        force_design_cutoff_hz=force_design, config=cfg)
