"""The trial as the stages see it: filtered markers, per-foot loads, events and what was done to them.

Model axes (x forward along the walk, y left, z up), SI units, time in seconds
from the first marker frame; every array runs over the marker frames. The
filter stage makes a :class:`Trial` from a :class:`~gaitcli.core.recording.Recording`;
every later stage reads it (from memory or from ``filter.h5``) and never the
CSV tables.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from gaitcli.core.events import SIDES, Events
from gaitcli.core.numerics import frame_ranges
from gaitcli.core.recording import Markers


@dataclass(frozen=True)
class FootLoad:
    """The ground reaction on one foot, summed over the plates it stood on (marker frames).

    ``force_N`` (n, 3) the force of the ground on the foot (zero where unloaded);
    ``cop_m`` (n, 3) its centre of pressure on the floor (NaN where unloaded);
    ``free_moment_Nm`` (n,) the vertical free moment about the COP (NaN where
    unloaded); ``known`` (n,) whether the foot's load is known in that frame: in
    swing, or standing on a plate. ``on_plates``: whether any plate measured
    this foot at all.
    """

    force_N: np.ndarray
    cop_m: np.ndarray
    free_moment_Nm: np.ndarray
    known: np.ndarray
    on_plates: bool = True

    @classmethod
    def unmeasured(cls, n: int, known: np.ndarray) -> FootLoad:
        """A foot no plate saw: zero force, NaN COP and free moment; ``known`` in swing only."""
        return cls(np.zeros((n, 3)), np.full((n, 3), np.nan), np.full(n, np.nan), np.asarray(known, bool),
                   on_plates=False)


@dataclass(frozen=True)
class Trial:
    """Filtered markers, the load on each foot, gait events and the processing history.

    ``feet`` has both sides, ``"r"`` and ``"l"``. ``history``: one line per
    processing step, in order (written into every HDF5 file's attributes).
    ``lab_to_model`` (3, 3): the rotation from the lab's axes, ``v_model = R @ v_lab``
    (a standing trial read later is turned the same way). ``subject_metadata``: what the
    trial file records about the subject (:class:`~gaitcli.core.recording.Recording`). ``marker_labels``: the
    lab label of each marker the marker set renamed {landmark: lab label} (the exports write the lab's labels).
    ``filter_edge_frames``: the frames at each end of a filtered marker run whose accelerations the zero-lag
    filter's start-up corrupts (:func:`~gaitcli.signal.butterworth.edge_frames`; 0: not filtered).
    """

    markers: Markers
    feet: dict[str, FootLoad]
    events: Events
    history: tuple[str, ...] = ()
    source: str = ""
    lab_to_model: np.ndarray | None = None
    subject_metadata: dict[str, float] = dataclasses.field(default_factory=dict)
    marker_labels: dict[str, str] = dataclasses.field(default_factory=dict)
    filter_edge_frames: int = 0

    @property
    def time_s(self) -> np.ndarray:
        return self.markers.time_s

    @property
    def n_frames(self) -> int:
        return self.markers.n_frames

    @property
    def rate_hz(self) -> float:
        return self.markers.rate_hz

    def load_known(self, side: str) -> np.ndarray:
        """(n,) frames in which the load on ``side``'s foot is known (its leg's joint moments are right)."""
        return self.feet[side].known

    @property
    def all_loads_known(self) -> np.ndarray:
        """(n,) frames in which every foot on the ground stands on a plate (the pelvis residuals are right)."""
        return np.logical_and.reduce([self.feet[s].known for s in SIDES])

    def with_step(self, line: str, **changes) -> Trial:
        """A copy with ``line`` appended to the history (and fields replaced)."""
        return dataclasses.replace(self, history=self.history + (line,), **changes)


#: s: a stance's frames this close before its plate's first loaded frame, or after its last, are the plate's
#: (the foot landing or leaving with less than the plate's threshold: a lab's events often come a frame or
#: two before the plate's onset)
EVENT_SLACK_S = 0.02


def load_known_frames(events: Events, time_s: np.ndarray, loaded: np.ndarray, side: str) -> np.ndarray:
    """Frames in which a foot's load is known: in swing, or loaded (on a plate) during its stance, or within
    :data:`EVENT_SLACK_S` of a loaded run at either end of a stance (below the plate's threshold there).

    Stance runs from each heel strike to the next toe off (or the trial's end), and
    from the start to the first toe off when the trial begins in stance.
    """
    stance = events.stance_mask(side, time_s)
    known = ~stance | np.asarray(loaded, dtype=bool)
    for start, end in frame_ranges(np.flatnonzero(stance)):
        on = np.flatnonzero(known[start:end + 1]) + start
        if on.size == 0:
            continue
        near_start = time_s[start:on[0]] >= time_s[on[0]] - EVENT_SLACK_S
        if near_start.all():  # the whole start of the stance, up to its plate's onset
            known[start:on[0]] = True
        near_end = time_s[on[-1] + 1:end + 1] <= time_s[on[-1]] + EVENT_SLACK_S
        if near_end.all():
            known[on[-1] + 1:end + 1] = True
    return known

