"""Lab axes → model axes (x forward along the walk, y left, z up), a proper rotation.

``R = infer_lab_to_model(markers_lab, plates_lab)`` returns the (3, 3) rotation
with ``v_model = R @ v_lab``; its rows are the model axes written in lab
coordinates. Only a rotation: the lab origin (usually on the floor) is kept.

Rules (one place, used by the C3D and the CSV readers):

* **Vertical.** If any plate is loaded (some sample with ``|F| > 20 N``), up is
  the direction of the summed ground-on-subject force over the loaded samples
  (the feet push the subject up). Otherwise the markers decide: the lab axis
  with the largest median per-frame marker extent (a standing or walking body
  is taller than it is wide or deep; checked on every shared lab file), signed
  so that the markers' mean coordinate along it is positive (lab origins sit on
  the floor, the subject above it). The vertical is snapped to the nearest lab
  axis (±x, ±y or ±z).
* **Forward.** The horizontal part of the markers' mean displacement over the
  trial, each marker taken from its first to its last visible frame (equal to
  the centroid displacement when no marker is lost, and unaffected by markers
  appearing or vanishing). The subject walks toward model +x. Snapped to a
  horizontal lab axis when within 10° of it, else kept exact.
* **Static trials** (mean displacement below 0.2 m, too few frames or no
  visible markers, e.g. a 2-frame file or a standing trial): forward falls back
  to the first lab axis that is not vertical (lab x, or lab y when x is
  vertical), so only the vertical is fixed.
* ``y = z × x``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from gaitcli.core.recording import ForcePlate, Markers, Recording

__all__ = [
    "LOAD_THRESHOLD_N",
    "apply_rotation",
    "forward_direction",
    "infer_lab_to_model",
    "rotate_markers",
    "rotate_plate",
    "snap_to_axis",
    "vertical_from_markers",
    "vertical_from_plates",
]

LOAD_THRESHOLD_N = 20.0
"""A plate sample counts as loaded above this force (N)."""

STATIC_DISPLACEMENT_M = 0.2
"""Below this mean marker displacement (m) a trial counts as static (no walking direction)."""

SNAP_ANGLE_DEG = 10.0
"""A forward direction this close to a lab axis (degrees) is snapped onto it."""

_AXES = np.eye(3)


def snap_to_axis(v) -> np.ndarray:
    """The signed lab unit axis (±e_x, ±e_y, ±e_z) nearest to direction ``v`` (3,)."""
    v = np.asarray(v, dtype=float)
    i = int(np.argmax(np.abs(v)))
    return np.sign(v[i]) * _AXES[i]


def vertical_from_plates(plates: list[ForcePlate], *, threshold_N: float = LOAD_THRESHOLD_N):
    """Unit up direction (3,) from the summed loaded ground-on-subject forces, or None if no plate is loaded."""
    total = np.zeros(3)
    for plate in plates:
        f = np.asarray(plate.force_N, dtype=float)
        loaded = np.linalg.norm(f, axis=1) > threshold_N
        total += np.nansum(f[loaded], axis=0)
    norm = np.linalg.norm(total)
    return total / norm if norm > 0 else None


def vertical_from_markers(positions: np.ndarray):
    """Signed lab axis (3,) that is up, judged from marker positions (frames, markers, 3); None if none is seen."""
    p = np.asarray(positions, dtype=float)
    seen = np.isfinite(p).all(axis=2)
    if not seen.any():
        return None
    frames = seen.sum(axis=1) >= 2
    if frames.any():
        q = p[frames]
        extent = np.nanmax(q, axis=1) - np.nanmin(q, axis=1)  # (frames, 3) body extent per frame
        i = int(np.argmax(np.nanmedian(extent, axis=0)))
    else:
        i = 2
    mean = np.nanmean(p[..., i][seen])
    return (1.0 if mean >= 0 else -1.0) * _AXES[i]


def forward_direction(positions: np.ndarray, up: np.ndarray):
    """Horizontal unit walking direction (3,) from the markers' mean displacement, or None when static.

    Each marker contributes its displacement from its first to its last visible
    frame; the mean over markers seen in at least two frames is projected on the
    plane normal to ``up``. None when that displacement is below 0.2 m.
    """
    p = np.asarray(positions, dtype=float)
    if p.ndim != 3 or p.shape[0] < 2 or p.shape[1] == 0:
        return None
    seen = np.isfinite(p).all(axis=2)  # (frames, markers)
    n = p.shape[0]
    first = np.argmax(seen, axis=0)
    last = n - 1 - np.argmax(seen[::-1], axis=0)
    use = seen.any(axis=0) & (last > first)
    if not use.any():
        return None
    cols = np.flatnonzero(use)
    d = (p[last[cols], cols] - p[first[cols], cols]).mean(axis=0)
    d_h = d - np.dot(d, up) * up
    norm = np.linalg.norm(d_h)
    if norm < STATIC_DISPLACEMENT_M:
        return None
    return d_h / norm


def infer_lab_to_model(markers_lab: np.ndarray, plates_lab: list[ForcePlate] = ()) -> np.ndarray:
    """Rotation (3, 3) lab → model, ``v_model = R @ v_lab``, by the rules of the module docstring.

    ``markers_lab``: positions (frames, markers, 3) in lab axes (NaN where not
    seen); ``plates_lab``: force plates in lab axes, ground-on-subject force.
    """
    up = vertical_from_plates(list(plates_lab))
    if up is None:
        up = vertical_from_markers(markers_lab)
    z = _AXES[2] if up is None else snap_to_axis(up)
    x = forward_direction(markers_lab, z)
    if x is None:
        vertical_index = int(np.argmax(np.abs(z)))
        x = _AXES[1] if vertical_index == 0 else _AXES[0]
    else:
        horizontal = [a for i, a in enumerate(_AXES) if abs(z[i]) < 0.5]
        candidates = np.array([s * a for a in horizontal for s in (1.0, -1.0)])
        cosines = candidates @ x
        best = int(np.argmax(cosines))
        if cosines[best] >= np.cos(np.radians(SNAP_ANGLE_DEG)):
            x = candidates[best]
    y = np.cross(z, x)
    return np.stack([x, y, z])


def rotate_markers(markers: Markers, R: np.ndarray) -> Markers:
    """Markers with positions rotated, ``p' = R @ p`` for every frame and marker."""
    return replace(markers, positions_m=np.asarray(markers.positions_m, dtype=float) @ np.asarray(R).T)


def rotate_plate(plate: ForcePlate, R: np.ndarray) -> ForcePlate:
    """Force plate with force, moment, centre and corners rotated by ``R`` (moment still about the same point)."""
    R = np.asarray(R, dtype=float)
    return replace(
        plate,
        force_N=plate.force_N @ R.T,
        moment_Nm=plate.moment_Nm @ R.T,
        centre_m=R @ plate.centre_m,
        corners_m=plate.corners_m @ R.T,
    )


def apply_rotation(recording: Recording, R: np.ndarray) -> Recording:
    """Recording with markers and plates rotated by ``R``; ``lab_to_model`` becomes ``R @ lab_to_model``."""
    R = np.asarray(R, dtype=float)
    return replace(
        recording,
        markers=rotate_markers(recording.markers, R),
        plates=[rotate_plate(p, R) for p in recording.plates],
        lab_to_model=R @ np.asarray(recording.lab_to_model, dtype=float),
        notes=list(recording.notes),
    )
