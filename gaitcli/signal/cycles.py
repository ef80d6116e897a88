"""Gait cycles from events: strides, time normalisation to 0–100 %, and the features of Table 3.1."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.core.events import Events

#: points of a time-normalised cycle, and their percentages of the cycle: 0, 1, …, 100 %
CYCLE_POINTS = 101
CYCLE_PCT = np.arange(CYCLE_POINTS, dtype=float)


@dataclass(frozen=True)
class Stride:
    """One gait cycle of one side: heel strike to the next heel strike of the same foot (times in s)."""

    side: str
    start_s: float
    end_s: float
    toe_off_s: float  # this foot's toe off inside the stride (NaN if not seen)

    @property
    def period_s(self) -> float:
        return self.end_s - self.start_s


def strides(events: Events) -> list[Stride]:
    """Every complete stride of both sides, in time order; not a gap between heel strikes longer than a walking
    stride (:data:`WALKING_PERIOD_S`: the foot's strikes in between were not recorded)."""
    out = []
    for side in ("r", "l"):
        strikes, offs = events.times(side, "heel_strike"), events.times(side, "toe_off")
        for a, b in zip(strikes[:-1], strikes[1:]):
            if b - a > WALKING_PERIOD_S[1]:
                continue
            inside = offs[(offs > a) & (offs < b)]
            out.append(Stride(side, float(a), float(b), float(inside[0]) if inside.size else np.nan))
    return sorted(out, key=lambda s: s.start_s)


#: a walking stride: its period (s) and its stance (% of the period) within these (outside, the events cannot
#: describe walking: a lab's damaged or random EVENT group)
WALKING_PERIOD_S = (0.5, 3.0)
WALKING_STANCE_PCT = (40.0, 80.0)


#: where the other foot strikes in a walking stride (% of it): the feet alternate
OTHER_STRIKE_PCT = (25.0, 75.0)


def walking_events(events: Events) -> tuple[Events, list[tuple[str, float, float, str]]]:
    """``events`` without those that cannot describe walking, and what was set aside: (side, start s, end s,
    reason) per stride (:func:`_walking_pass`, repeated until nothing more goes: a stride its removals form is
    checked too)."""
    set_aside = []
    while True:
        kept, more = _walking_pass(events)
        set_aside += more
        if len(kept) == len(events):
            return kept, sorted(set_aside, key=lambda item: item[1])
        events = kept


def _walking_pass(events: Events) -> tuple[Events, list[tuple[str, float, float, str]]]:
    """One pass of :func:`walking_events`. Per foot, in time order: a heel strike less than
    :data:`WALKING_PERIOD_S`'s shortest period after the one kept before it goes, and the first of two toe offs
    with no heel strike between outside the foot's strides. Then per stride between kept
    heel strikes: longer than the longest period, it is no stride (:func:`strides`); where the other foot strikes
    more than once in it, or once outside :data:`OTHER_STRIKE_PCT` of it (none: its strike was not recorded), the
    stride's first heel strike and its toe offs go; of two or more toe offs only the one whose stance lies within
    :data:`WALKING_STANCE_PCT` stays (none where several or none do); a single one whose stance lies outside goes
    (the stride's stance then unknown)."""
    keep = np.ones(len(events.time_s), bool)
    set_aside = []
    low, high = WALKING_PERIOD_S
    kept = {}
    for side in ("r", "l"):
        strikes = np.flatnonzero(events.mask(side, "heel_strike"))
        kept[side] = []
        for k in strikes[np.argsort(events.time_s[strikes], kind="stable")]:
            t = events.time_s[k]
            if kept[side] and t - events.time_s[kept[side][-1]] < low:
                keep[k] = False
                set_aside.append((side, float(events.time_s[kept[side][-1]]), float(t),
                                  f"a heel strike {t - events.time_s[kept[side][-1]]:.3g} s after the one before "
                                  f"(expected a stride of {low:g}–{high:g} s)"))
            else:
                kept[side].append(k)
    for side in ("r", "l"):  # a foot leaves the ground once between two landings (inside a stride: below)
        offs = np.flatnonzero(events.mask(side, "toe_off"))
        offs = offs[np.argsort(events.time_s[offs], kind="stable")]
        strikes = events.time_s[kept[side]]
        for a, b in zip(offs[:-1], offs[1:]):
            inside_a_stride = strikes.size and strikes[0] < events.time_s[a] < strikes[-1]
            if not inside_a_stride and not np.any((strikes > events.time_s[a]) & (strikes < events.time_s[b])):
                keep[a] = False
                set_aside.append((side, float(events.time_s[a]), float(events.time_s[b]),
                                  "two toe offs with no heel strike between"))
    for side, other in (("r", "l"), ("l", "r")):
        offs = np.flatnonzero(events.mask(side, "toe_off") & keep)
        other_strikes = events.time_s[kept[other]]
        for a, b in zip(kept[side][:-1], kept[side][1:]):
            start, end = events.time_s[a], events.time_s[b]
            if not keep[a] or end - start > high:
                if end - start > high:
                    set_aside.append((side, float(start), float(end), f"period {end - start:.3g} s (expected "
                                                                        f"{low:g}–{high:g} s)"))
                continue
            inside = offs[(events.time_s[offs] > start) & (events.time_s[offs] < end)]
            crossing = 100 * (other_strikes[(other_strikes > start) & (other_strikes < end)] - start) / (end - start)
            if crossing.size > 1 or (crossing.size == 1 and not OTHER_STRIKE_PCT[0] <= crossing[0]
                                     <= OTHER_STRIKE_PCT[1]):
                keep[[a, *inside]] = False
                said = f"at {crossing[0]:.0f} %" if crossing.size == 1 else f"{crossing.size} times"
                set_aside.append((side, float(start), float(end), f"the other foot strikes {said} in it (expected "
                                  f"once, at {OTHER_STRIKE_PCT[0]:g}–{OTHER_STRIKE_PCT[1]:g} %)"))
            elif inside.size:
                stance = 100 * (events.time_s[inside] - start) / (end - start)
                walking = (stance >= WALKING_STANCE_PCT[0]) & (stance <= WALKING_STANCE_PCT[1])
                if inside.size > 1:  # one of them a walking stance: that one stays
                    keep[inside] = walking if np.count_nonzero(walking) == 1 else False
                    set_aside.append((side, float(start), float(end), f"{inside.size} toe offs of one foot in it"
                                      + (f" (the one at {stance[walking][0]:.0f} % kept)"
                                         if np.count_nonzero(walking) == 1 else "")))
                elif not walking[0]:
                    keep[inside] = False
                    set_aside.append((side, float(start), float(end), f"stance {stance[0]:.0f} % (expected "
                                      f"{WALKING_STANCE_PCT[0]:g}–{WALKING_STANCE_PCT[1]:g} %)"))
    return events.select(keep), set_aside


def normalise(values: np.ndarray, time_s: np.ndarray, stride: Stride) -> np.ndarray:
    """Resample ``values`` (frames, ...) over one stride to 101 points, 0–100 % (linear interpolation)."""
    grid = np.linspace(stride.start_s, stride.end_s, CYCLE_POINTS)
    flat = values.reshape(values.shape[0], -1)
    out = np.column_stack([np.interp(grid, time_s, flat[:, k], left=np.nan, right=np.nan)
                           for k in range(flat.shape[1])])
    return out.reshape((CYCLE_POINTS,) + values.shape[1:])


@dataclass(frozen=True)
class GaitFeatures:
    """Table 3.1: stride length (m), period (s), speed (m/s), stance % per side, double stance %; and each side's
    step length and the step width (m, :func:`steps`).

    Means over the complete strides of both sides; NaN where the events do not allow it.
    """

    stride_length_m: float
    period_s: float
    speed_m_s: float
    stance_right_pct: float
    stance_left_pct: float
    double_stance_pct: float
    strides: int
    step_length_right_m: float = float("nan")
    step_length_left_m: float = float("nan")
    step_width_m: float = float("nan")

    def as_dict(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def footprint(heel: np.ndarray, time_s: np.ndarray, strike_s: float, period_s: float) -> np.ndarray:
    """Position of a planted heel (``heel``: (frames,) forward or (frames, k) positions, m): where its forward
    position moves least in the first 35 % of the cycle after a strike.

    Robust to heel strikes timed a few frames early or late (kinematic events),
    unlike the heel position at the strike itself, when the heel still moves.
    """
    heel = np.asarray(heel, float).reshape(len(time_s), -1)
    window = (time_s >= strike_s) & (time_s <= strike_s + 0.35 * period_s) & np.all(np.isfinite(heel), axis=1)
    if window.sum() < 3:
        return np.array([np.interp(strike_s, time_s, heel[:, k]) for k in range(heel.shape[1])])
    speed = np.abs(np.gradient(heel[window, 0], time_s[window]))
    return heel[window][np.argmin(speed)]


@dataclass(frozen=True)
class Step:
    """One step: the foot ``side`` planted at ``strike_s`` (s) ahead of the other foot's last footprint; length
    along the walk (x) and width across it (y), m."""

    side: str
    strike_s: float
    length_m: float
    width_m: float


def footprints(events: Events, heel_m: dict[str, np.ndarray], time_s: np.ndarray,
               period_s: float) -> dict[str, dict[float, np.ndarray]]:
    """Each heel's footprint (:func:`footprint`) at each of its foot's heel strikes: side → {strike (s): position}."""
    return {side: {float(t): footprint(heel, time_s, float(t), period_s) for t in events.times(side, "heel_strike")}
            for side, heel in heel_m.items()}


def _steps(prints: dict[str, dict[float, np.ndarray]]) -> list[Step]:
    """The steps between the footprints of both feet (:func:`steps`), in time order."""
    out = []
    for side, other in (("r", "l"), ("l", "r")):
        if side not in prints or other not in prints:
            continue
        others = np.array(sorted(prints[other]))
        for strike, here in prints[side].items():
            before = others[others < strike]
            if not before.size:
                continue
            there = prints[other][float(before[-1])]
            out.append(Step(side, strike, float(abs(here[0] - there[0])), float(abs(here[1] - there[1]))))
    return sorted(out, key=lambda step: step.strike_s)


def steps(events: Events, heel_m: dict[str, np.ndarray], time_s: np.ndarray) -> list[Step]:
    """Every step whose two footprints (:func:`footprint`) are seen: ``heel_m[side]`` (frames, 2) the heel's
    forward and lateral position (m, model axes: x along the walk, y left); in time order."""
    periods = [st.period_s for st in strides(events)]
    return _steps(footprints(events, heel_m, time_s, float(np.mean(periods)) if periods else 1.0))


def gait_features(events: Events, heel_m: dict[str, np.ndarray], time_s: np.ndarray) -> GaitFeatures:
    """Table 3.1 from events and each heel's position (m) over time: (frames,) forward, or (frames, 2) forward
    and lateral (then the steps too, :func:`steps`).

    Stride length is the forward distance between two successive footprints of
    the same heel (mean over strides), the period the time between the strikes. Stance % is
    the stance time over the mean period, and double stance % the time both feet
    are on the ground, stance_r + stance_l − 100 (walking has no flight phase).
    Stances timed by a force plate at both ends are used where there are any,
    being exact; kinematic events (Zeni) time heel strike a few frames early and
    are the fallback.
    """
    def mean(v):
        return float(np.mean(v)) if len(v) else float("nan")

    all_strides = strides(events)
    period = mean([st.period_s for st in all_strides])
    prints = footprints(events, heel_m, time_s, period)  # each once: the strides and the steps share them
    lengths = [abs(prints[st.side][st.end_s][0] - prints[st.side][st.start_s][0]) for st in all_strides
               if st.side in prints]
    stance = {}
    for side in ("r", "l"):
        contacts = events.stances(side, "plate") or events.stances(side)
        stance[side] = mean([(b - a) / period * 100 for a, b in contacts])
    # walking has no flight phase: each foot's stance overlaps the other's twice per stride
    double = stance["r"] + stance["l"] - 100.0
    length = mean(lengths)
    lateral = {s: p for s, p in prints.items() if np.ndim(heel_m[s]) == 2 and np.shape(heel_m[s])[1] >= 2}
    found = _steps(lateral) if len(lateral) == 2 else []
    return GaitFeatures(stride_length_m=length, period_s=period,
                        speed_m_s=length / period if np.isfinite(length) and period > 0 else float("nan"),
                        stance_right_pct=stance["r"], stance_left_pct=stance["l"],
                        double_stance_pct=double, strides=len(all_strides),
                        step_length_right_m=mean([st.length_m for st in found if st.side == "r"]),
                        step_length_left_m=mean([st.length_m for st in found if st.side == "l"]),
                        step_width_m=mean([st.width_m for st in found]))
