"""Filling short marker gaps by cubic interpolation (3.1.4).

A marker that no camera pair sees has no 3-D position in that frame (NaN). Short
interior gaps are estimated by interpolation; the dissertation notes that this is
only meaningful for short periods, so gaps longer than a limit, and gaps at the
start or end of the trial (which would need extrapolation), stay NaN, and the body
the marker tracks is untracked there (NaN: a smaller cluster would jump).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from gaitcli.core.numerics import true_runs
from gaitcli.errors import InputError, shown

__all__ = ["Gap", "find_gaps", "fill_gaps"]


@dataclass(frozen=True)
class Gap:
    """One run of frames (inclusive, 0-based) in which marker ``marker_index`` has no position."""

    marker_index: int
    first_frame: int
    last_frame: int
    n_frames: int
    filled: bool


def find_gaps(positions, /) -> list[tuple[int, int, int]]:
    """``(marker_index, first_frame, last_frame)`` of every gap in ``positions`` (frames, markers, 3).

    A marker is missing in a frame when any of its coordinates is NaN. Ordered by
    marker, then frame.
    """
    missing = _missing(positions)
    gaps = []
    for m in range(missing.shape[1]):
        starts, stops = true_runs(missing[:, m])
        gaps.extend((m, int(a), int(b) - 1) for a, b in zip(starts, stops))
    return gaps


def fill_gaps(positions, /, *, max_gap_frames: int) -> tuple[np.ndarray, list[Gap]]:
    """Fill interior gaps of at most ``max_gap_frames`` frames by cubic-spline interpolation.

    For each marker with a fillable gap, a not-a-knot cubic spline through all its
    complete frames is evaluated in the gap frames. Gaps longer than the limit or
    touching the first or last frame are NaN in all three coordinates.

    Parameters
    ----------
    positions : array_like
        (frames, markers, 3), m; NaN where a marker is missing (a frame with any NaN
        coordinate counts as missing for all three).
    max_gap_frames : int
        Longest gap that is filled, frames.

    Returns
    -------
    filled : numpy.ndarray
        A new array (the input is not modified).
    gaps : list of Gap
        Every gap, ``filled=False`` for those left NaN.
    """
    if (isinstance(max_gap_frames, bool) or not isinstance(max_gap_frames, (int, np.integer))
            or max_gap_frames < 0):
        raise InputError(None, "max_gap_frames", f"got {shown(max_gap_frames)} (expected an integer >= 0)")
    missing = _missing(positions)
    filled = np.array(positions, dtype=float, copy=True)
    n_frames = filled.shape[0]
    filled[missing] = np.nan
    frames = np.arange(n_frames)
    gaps: list[Gap] = []
    for m, first, last in find_gaps(filled):
        length = last - first + 1
        interior = first > 0 and last < n_frames - 1
        gaps.append(Gap(m, first, last, length, interior and length <= max_gap_frames))
    by_marker: dict[int, list[Gap]] = {}
    for gap in gaps:
        if gap.filled:
            by_marker.setdefault(gap.marker_index, []).append(gap)
    for m, marker_gaps in by_marker.items():
        known = ~missing[:, m]
        spline = CubicSpline(frames[known], filled[known, m, :], axis=0)
        target = np.concatenate([np.arange(g.first_frame, g.last_frame + 1) for g in marker_gaps])
        filled[target, m, :] = spline(target)
    return filled, gaps


def _missing(positions) -> np.ndarray:
    positions = np.asarray(positions, dtype=float)
    if positions.ndim != 3 or positions.shape[2] != 3:
        raise InputError(None, "positions", f"got shape {positions.shape} (expected (frames, markers, 3))")
    return ~np.isfinite(positions).all(axis=2)
