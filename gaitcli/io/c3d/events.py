"""C3D gait events: the EVENT group (LABELS, CONTEXTS, TIMES, USED) as :class:`~gaitcli.core.events.Events`.

EVENT:TIMES holds minutes (row 0) and seconds (row 1) from the recording's frame 1, the way Vicon
Nexus, Qualisys and ezc3d's readers count: the trial's first frame (POINT first frame ``f``, 1-based)
is at ``(f - 1) / rate``. On the trial's own time axis (0 at its first frame) an event is at
``60 min + s - (f - 1) / rate``. Gait events are "Foot Strike" (or "Heel Strike") and "Foot Off" (or
"Toe Off") with the context "Left"/"Right", or short labels that carry the side (``LHS``, ``RTO``,
``LFS``, ``RFO``, ...); others ("Event", "General", ...) are not gait events and are left out.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from gaitcli.core.events import Events
from gaitcli.io.c3d.header import param, strings, warn

__all__ = ["read_events", "gait_event", "EVENT_LABELS", "EVENT_CONTEXTS"]

#: gaitcli's kinds and sides as Vicon Nexus labels and contexts
EVENT_LABELS = {"heel_strike": "Foot Strike", "toe_off": "Foot Off"}
EVENT_CONTEXTS = {"r": "Right", "l": "Left"}

_KINDS = {"foot strike": "heel_strike", "heel strike": "heel_strike", "initial contact": "heel_strike",
          "foot off": "toe_off", "toe off": "toe_off", "hs": "heel_strike", "fs": "heel_strike",
          "ic": "heel_strike", "to": "toe_off", "fo": "toe_off"}
_SIDES = {"left": "l", "right": "r", "l": "l", "r": "r"}
_SHORT = re.compile(r"^(l|r|left|right)[ _.:-]*(hs|fs|ic|to|fo|foot strike|foot off|heel strike|toe off)$")


def gait_event(label: str, context: str = "") -> tuple[str, str] | None:
    """(side, kind) of one C3D event, or None where it is not a gait event with a side."""
    text = " ".join(label.lower().replace("_", " ").split())
    side = _SIDES.get(context.strip().lower())
    if text in _KINDS:  # "Foot Strike" and its kin: the side is the context
        return (side, _KINDS[text]) if side else None
    match = _SHORT.match(text)
    if match:
        return _SIDES[match.group(1)], _KINDS[match.group(2)]
    return None


def _decimal(value: float) -> float:
    """A time stored as a 32-bit float as the shortest decimal that gives it (3.5899999141693115 → 3.59)."""
    value = np.float32(value)
    return float(np.format_float_positional(value, unique=True)) if np.isfinite(value) else float(value)


def read_events(path: Path, params, *, rate_hz: float, first_frame: int, n_frames: int,
                notes: list[str]) -> Events:
    """The gait events of the EVENT group in seconds from the trial's first frame (source ``file``).

    ``first_frame``: the POINT first frame, 1-based. Events whose nearest frame lies outside the trial's
    ``n_frames`` are dropped, as are repeats (same side, kind and frame); both are warned. A group whose
    parts do not fit together (TIMES not 2 × n, fewer LABELS than USED) is warned and gives no events.
    """
    if "EVENT" not in params:
        return Events()
    times = param(params, "EVENT", "TIMES")
    labels = strings(params, "EVENT", "LABELS")
    contexts = strings(params, "EVENT", "CONTEXTS")
    if times is None or not labels:
        return Events()
    times = np.asarray(times, dtype=float)
    if times.ndim == 1 and times.size == 2 * len(labels):
        times = times.reshape(len(labels), 2).T
    used = param(params, "EVENT", "USED")
    try:
        n = int(np.asarray(used).ravel()[0]) if used is not None and np.size(used) else len(labels)
    except (TypeError, ValueError):
        n = len(labels)
    if times.ndim != 2 or times.shape[0] != 2 or times.shape[1] < n or len(labels) < n or n < 0:
        warn(f"{path.name}: EVENT group ignored: USED {n}, {len(labels)} LABELS, TIMES of shape "
             f"{times.shape} (expected 2 × USED times and USED labels)", notes)
        return Events()
    contexts = contexts[:n] + [""] * max(0, n - len(contexts))
    start_s = (first_frame - 1) / rate_hz
    found, outside, sideless = [], [], 0
    for k in range(n):
        which = gait_event(labels[k], contexts[k])
        if which is None:
            if gait_event(labels[k], "Left") is not None:  # a gait event whose context names no side
                sideless += 1
            continue
        t_file = 60.0 * _decimal(times[0, k]) + _decimal(times[1, k])
        if not np.isfinite(t_file):
            outside.append(t_file)
            continue
        t = round(t_file - start_s, 9)
        frame = int(np.rint(t * rate_hz))
        if not 0 <= frame < n_frames:
            outside.append(t_file)
            continue
        found.append((t, frame, *which))
    if sideless:
        warn(f"{path.name}: EVENT: {sideless} foot event(s) without a Left/Right context left out", notes)
    if outside:
        listed = ", ".join(f"{t:.3f}" for t in outside[:6]) + (" ..." if len(outside) > 6 else "")
        warn(f"{path.name}: EVENT: {len(outside)} gait event(s) outside the trial's "
             f"{start_s:.3f}–{start_s + (n_frames - 1) / rate_hz:.3f} s dropped (at {listed} s)", notes)
    seen, kept = set(), []
    for event in found:
        key = (event[1], event[2], event[3])
        if key not in seen:
            seen.add(key)
            kept.append(event)
    if len(kept) < len(found):
        warn(f"{path.name}: EVENT: {len(found) - len(kept)} repeated gait event(s) (same side, kind and frame) "
             "left out", notes)
    if not kept:
        return Events()
    t, frame, side, kind = (np.array(v) for v in zip(*kept))
    notes.append(f"{len(kept)} gait events read from the EVENT group")
    return Events(frame.astype(int), t.astype(float), side, kind, np.full(len(kept), "file"))
