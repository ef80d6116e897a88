"""Gait events (heel strike, toe off of each foot) and the queries the stages ask of them.

Times in seconds from the first marker frame; frames are 0-based indices into
the marker arrays. The detection lives in :mod:`gaitcli.signal.events`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gaitcli.core.validate import one_of
from gaitcli.errors import InputError

SIDES = ("r", "l")
SIDE_NAMES = {"r": "right", "l": "left"}
KINDS = ("heel_strike", "toe_off")
SOURCES = ("plate", "kinematics", "file")


@dataclass(frozen=True)
class Events:
    """Gait events as parallel arrays, sorted by time.

    ``frame`` (int, 0-based marker frame nearest to the event), ``time_s``,
    ``side`` (``'r'``/``'l'``), ``kind`` (``'heel_strike'``/``'toe_off'``) and
    ``source`` (``'plate'``/``'kinematics'`` detected, ``'file'`` from the trial file's own events).
    """

    frame: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    time_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    side: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U1"))
    kind: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U11"))
    source: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype="<U10"))

    def __post_init__(self):
        frame = np.asarray(self.frame, dtype=int).ravel()
        time_s = np.asarray(self.time_s, dtype=float).ravel()
        text = {}
        for name, allowed, dtype in (("side", SIDES, "<U1"), ("kind", KINDS, "<U11"), ("source", SOURCES, "<U10")):
            values = np.asarray(getattr(self, name)).astype(str).ravel()  # checked before the fixed width cuts
            for value in sorted(set(values.tolist()) - set(allowed)):
                one_of(value, allowed, where=f"events.{name}")
            text[name] = values.astype(dtype)
        side, kind, source = text["side"], text["kind"], text["source"]
        if not len(frame) == len(time_s) == len(side) == len(kind) == len(source):
            raise InputError(None, "events", "got arrays of different lengths (expected parallel arrays)")
        order = np.lexsort((kind, side, time_s))
        for name, values in (("frame", frame), ("time_s", time_s), ("side", side), ("kind", kind),
                             ("source", source)):
            object.__setattr__(self, name, values[order])

    @classmethod
    def from_times(cls, time_s, *, rate_hz: float, side: str, kind: str, source: str) -> Events:
        """Events of one side, kind and source at ``time_s``; ``frame = round(time_s * rate_hz)``."""
        time_s = np.asarray(time_s, dtype=float).ravel()
        n = len(time_s)
        return cls(np.rint(time_s * rate_hz).astype(int), time_s, np.full(n, side), np.full(n, kind),
                   np.full(n, source))

    @classmethod
    def concatenate(cls, parts) -> Events:
        """All events of ``parts`` in one sorted :class:`Events`."""
        parts = list(parts)
        if not parts:
            return cls()
        return cls(*(np.concatenate([getattr(p, name) for p in parts])
                     for name in ("frame", "time_s", "side", "kind", "source")))

    def __len__(self) -> int:
        return len(self.time_s)

    def select(self, mask) -> Events:
        """The events where the boolean ``mask`` is true."""
        mask = np.asarray(mask, dtype=bool)
        return Events(self.frame[mask], self.time_s[mask], self.side[mask], self.kind[mask], self.source[mask])

    def mask(self, side: str | None = None, kind: str | None = None, source: str | None = None) -> np.ndarray:
        """(len,) where the events are of that side and/or kind and/or source (None: any)."""
        mask = np.ones(len(self), dtype=bool)
        for values, wanted in ((self.side, side), (self.kind, kind), (self.source, source)):
            if wanted is not None:
                mask &= values == wanted
        return mask

    def of(self, side: str | None = None, kind: str | None = None, source: str | None = None) -> Events:
        """The events of one side and/or kind and/or source (None: any)."""
        return self.select(self.mask(side, kind, source))

    def times(self, side: str, kind: str, source: str | None = None) -> np.ndarray:
        """Sorted times (s) of one side's events of one kind (and source, None: any)."""
        return np.sort(self.of(side=side, kind=kind, source=source).time_s)

    def stances(self, side: str, source: str | None = None, *, open_ends: bool = False,
                max_s: float = np.inf) -> list[tuple[float, float]]:
        """Stance intervals (heel strike → the next toe off, s) of ``side``.

        ``source``: both events from that source (None: any). A stance longer than
        ``max_s`` is not one. With ``open_ends`` a heel strike without a later toe
        off gives ``(strike, inf)`` and a toe off before the first heel strike
        ``(-inf, toe off)``: the foot is on the ground at an end of the trial.
        """
        strikes, offs = self.times(side, "heel_strike", source), self.times(side, "toe_off", source)
        out = []
        if open_ends and offs.size and (not strikes.size or offs[0] < strikes[0]):
            out.append((-np.inf, float(offs[0])))
        for a in strikes:
            later = offs[offs > a]
            if later.size and later[0] - a < max_s:
                out.append((float(a), float(later[0])))
            elif open_ends and not later.size:
                out.append((float(a), np.inf))
        return out

    def stance_mask(self, side: str, time_s: np.ndarray) -> np.ndarray:
        """(n,) the samples at ``time_s`` that lie in a stance of ``side`` (:meth:`stances` with open ends)."""
        time_s = np.asarray(time_s, dtype=float)
        mask = np.zeros(time_s.size, dtype=bool)
        for a, b in self.stances(side, open_ends=True):
            mask |= (time_s >= a) & (time_s <= b)
        return mask

    def swings(self, side: str) -> list[tuple[float, float]]:
        """Swing intervals (toe off → the next heel strike, s) of ``side``."""
        strikes = self.times(side, "heel_strike")
        out = []
        for off in self.times(side, "toe_off"):
            later = strikes[strikes > off]
            if later.size:
                out.append((float(off), float(later[0])))
        return out

    def rows(self) -> list[dict]:
        """One dict per event with keys ``time_s, frame, side, kind, source`` (for ``events.csv``)."""
        return [{"time_s": float(t), "frame": int(f), "side": str(s), "kind": str(k), "source": str(src)}
                for t, f, s, k, src in zip(self.time_s, self.frame, self.side, self.kind, self.source)]
