"""Numerics shared by the optimisations: finite-difference matrices and the scalings of the NLPs.

- :func:`finite_difference_matrix`: ẋ ≈ D·x on a uniform grid (4.10–4.12, 4.31, 4.33);
- :data:`MOMENT_SCALE_NM`: joint moments are divided by it inside the NLPs so that
  every constraint is O(1);
- :func:`stretch_from_force` / :func:`force_from_stretch`: the force variable of
  the MSO and EID NLPs, the normalised tendon stretch ŝ with F = F_max·ŝ² (2.19).
"""

from __future__ import annotations

import numpy as np

from gaitcli.core.validate import integer, one_of


def true_runs(mask) -> tuple[np.ndarray, np.ndarray]:
    """Start and stop (exclusive) indices of the runs of ``True`` in the 1-D boolean array ``mask``."""
    edges = np.diff(np.concatenate([[0], np.asarray(mask, dtype=np.int8), [0]]))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def frame_ranges(indices) -> list[tuple[int, int]]:
    """Consecutive runs ``(first, last)`` of sorted integer ``indices``."""
    idx = np.asarray(indices, dtype=int)
    if idx.size == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) != 1)
    starts = np.concatenate([[idx[0]], idx[breaks + 1]])
    ends = np.concatenate([idx[breaks], [idx[-1]]])
    return list(zip(starts.tolist(), ends.tolist()))


def frame_spans(indices, first_frame: int = 0) -> str:
    """Sorted 0-based frame ``indices`` as file frame numbers for people: ``"5–9, 12"``."""
    return ", ".join(f"{a + first_frame}" if a == e else f"{a + first_frame}–{e + first_frame}"
                     for a, e in frame_ranges(indices))


#: finite-difference schemes of :func:`finite_difference_matrix`
FINITE_DIFFERENCE_SCHEMES = ("periodic", "central", "backward")
#: moments are scaled by this (N·m) inside the NLPs so that all constraints are O(1)
MOMENT_SCALE_NM = 10.0


def finite_difference_matrix(n: int, dt: float, scheme: str) -> np.ndarray:
    """Matrix D (n × n) with ẋ ≈ D·x for samples x spaced ``dt`` s apart.

    ``scheme``: ``"periodic"`` central differences wrapping around (4.10, for a
    full cycle, one time step between the last and the first node);
    ``"central"`` central inside, forward at the first and backward at the last
    sample (4.10–4.12); ``"backward"`` backward differences (4.31, 4.33) with a
    forward difference at the first sample (4.4: first-frame treatment of MSO).
    Raises InputError for an unknown scheme or too few samples.
    """
    one_of(scheme, FINITE_DIFFERENCE_SCHEMES, where="scheme")
    integer(int(n), where="nodes", low=3 if scheme == "periodic" else 2)
    d = np.zeros((n, n))
    if scheme == "periodic":
        idx = np.arange(n)
        d[idx, (idx + 1) % n] = 1.0 / (2 * dt)
        d[idx, (idx - 1) % n] = -1.0 / (2 * dt)
    elif scheme == "central":
        idx = np.arange(1, n - 1)
        d[idx, idx + 1] = 1.0 / (2 * dt)
        d[idx, idx - 1] = -1.0 / (2 * dt)
        d[0, 0], d[0, 1] = -1.0 / dt, 1.0 / dt  # (4.12)
        d[n - 1, n - 2], d[n - 1, n - 1] = -1.0 / dt, 1.0 / dt  # (4.11)
    else:
        idx = np.arange(1, n)
        d[idx, idx] = 1.0 / dt
        d[idx, idx - 1] = -1.0 / dt
        d[0, 0], d[0, 1] = -1.0 / dt, 1.0 / dt
    return d


def stretch_from_force(force_N, max_force_N) -> np.ndarray:
    """Normalised tendon stretch ŝ = √(F/F_max) (2.19) of forces (n, m); negative forces count as 0."""
    return np.sqrt(np.maximum(np.asarray(force_N, float), 0.0) / max_force_N)


def force_from_stretch(stretch, max_force_N) -> np.ndarray:
    """Tendon force F = F_max·ŝ² (2.19) of normalised stretches (n, m); negative stretches count as 0."""
    return max_force_N * np.maximum(np.asarray(stretch, float), 0.0) ** 2
