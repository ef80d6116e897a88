"""Segment poses per frame and the 27 generalized coordinates (3.1, 3.3.1, 3.16–3.18).

Each tracked body is fitted on its own (the local optimisation of 3.3.1); the
coordinates then keep only what (3.1) needs: the pelvis CoM position, the pelvis
Cardan x-y-z angles (3.16) and for each joint the Cardan y-x-z angles (3.18) of
``S_rel = S_pᵀ S_d`` (3.17), stored as (flexion, adduction, rotation). Distal
segment positions follow from these by the joint constraints, as 3.3.2 describes
("the segments are moved translationally until the joint constraints are
matched"); ``joint_gap_m`` reports how far apart the independently fitted segments
put each joint centre. Angles are unwrapped over time.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from gaitcli.core.numerics import frame_spans
from gaitcli.core.recording import Markers
from gaitcli.core.validate import one_of
from gaitcli.kinematics.calibration import StaticCalibration
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINT_CHILD, JOINT_PARENT
from gaitcli.kinematics.pose import fit_rigid_pose
from gaitcli.kinematics.rotations import matrix_to_cardan_xyz, matrix_to_joint_angles


@dataclass
class SegmentPoses:
    """Poses of the 8 bodies over ``n`` frames (global = model axes, SI units).

    ``rotation`` (n, 8, 3, 3) maps body-frame vectors to global; ``com_m`` (n, 8, 3)
    the body-frame origin (the CoM); ``rms_m`` (n, 8) the marker fit residual (3.4)
    (NaN for locked bodies); ``markers_used`` (n, 8); ``missing_frames[body]`` the frame
    indices where a tracked body had fewer than 3 markers (NaN pose); ``joint_gap_m``
    (n, 7) the distance between each joint centre as placed by parent and by child;
    ``frames`` is ``"reference"`` or ``"anatomical"``.
    """

    rotation: np.ndarray
    com_m: np.ndarray
    rms_m: np.ndarray
    markers_used: np.ndarray
    missing_frames: dict[str, np.ndarray]
    joint_gap_m: np.ndarray
    locked: tuple[str, ...] = ()
    frames: str = "reference"
    rate_hz: float = 100.0
    first_frame: int = 1

    @property
    def n_frames(self) -> int:
        return self.rotation.shape[0]


def _joint_positions(rotation, com_m, joint_in_parent_m, joint_in_child_m):
    """Joint centres (n, 7, 3) as placed by the parent and by the child body."""
    by_parent = np.stack([com_m[:, p] + rotation[:, p] @ joint_in_parent_m[j]
                          for j, p in enumerate(JOINT_PARENT)], axis=1)
    by_child = np.stack([com_m[:, c] + rotation[:, c] @ joint_in_child_m[j]
                         for j, c in enumerate(JOINT_CHILD)], axis=1)
    return by_parent, by_child


def cluster_complete(current: np.ndarray) -> np.ndarray:
    """(n,) frames in which every point of a cluster (n, k, 3) that the trial shows at all is seen.

    A pose fitted to fewer points than the rest of the trial's is offset by those points' skin movement and
    noise: at an unfilled gap's ends it would jump, and its second derivative spike (several N·m/kg at a hip).
    So a body is untracked (NaN) wherever a point of its cluster is missing; a point the trial never shows does
    not count.
    """
    seen = np.all(np.isfinite(current), axis=-1)  # (n, k)
    shown = seen.any(axis=0)
    return np.all(seen[:, shown], axis=1)


def track_segments(markers: Markers, calibration: StaticCalibration) -> SegmentPoses:
    """Fit every tracked body's static cluster to each frame by SVD (3.2–3.15); locked bodies follow their parent,
    and a chained body's proximal joint centre is placed by its parent's fitted pose. A body is untracked (NaN)
    in the frames where a point of its cluster that the trial shows elsewhere is missing
    (:func:`cluster_complete`)."""
    n = markers.n_frames
    nb = len(BODIES)
    R = np.full((n, nb, 3, 3), np.nan)
    com = np.full((n, nb, 3), np.nan)
    rms = np.full((n, nb), np.nan)
    used = np.zeros((n, nb), dtype=int)
    missing: dict[str, np.ndarray] = {}
    jp, jc = calibration.body.joint_in_parent_m, calibration.body.joint_in_child_m
    for i, b in enumerate(BODIES):  # parents come before children in BODIES
        if b in calibration.locked:
            j = JOINT_CHILD.index(i)
            p = JOINT_PARENT[j]
            R[:, i] = R[:, p]
            com[:, i] = com[:, p] + R[:, p] @ (jp[j] - jc[j])
            continue
        labels = calibration.tracking_landmarks[b]
        current = np.stack([markers.get(lab) if lab in markers else np.full((n, 3), np.nan) for lab in labels],
                           axis=1)
        if b in calibration.chained:  # the proximal joint centre, where the parent's pose puts it
            j = JOINT_CHILD.index(i)
            p = JOINT_PARENT[j]
            current[:, labels.index(calibration.chained[b])] = com[:, p] + R[:, p] @ jp[j]
        current[~cluster_complete(current)] = np.nan
        fit = fit_rigid_pose(calibration.cluster(b), current)
        R[:, i], com[:, i], rms[:, i], used[:, i] = fit.R, fit.d_m, fit.rms_m, fit.markers_used
        missing[b] = fit.invalid_frames
    by_parent, by_child = _joint_positions(R, com, jp, jc)
    gap = np.linalg.norm(by_parent - by_child, axis=-1)
    return SegmentPoses(R, com, rms, used, missing, gap, tuple(calibration.locked), "reference",
                        markers.rate_hz, markers.first_frame)


def convert_frames(poses: SegmentPoses, calibration: StaticCalibration, frames: str) -> SegmentPoses:
    """Express ``poses`` in ``"reference"`` or ``"anatomical"`` frames (same origins; 3.3)."""
    one_of(frames, ("reference", "anatomical"), where="frames")
    if frames == poses.frames:
        return poses
    C = calibration.reference_to_anatomical  # R_anatomical = R_reference @ C
    if frames == "reference":
        C = np.swapaxes(C, -1, -2)
    return replace(poses, rotation=poses.rotation @ C, frames=frames)


def unwrap_angles(angles_rad, axis: int = 0) -> np.ndarray:
    """``np.unwrap`` along ``axis`` that skips NaN samples instead of spreading them."""
    a = np.moveaxis(np.array(angles_rad, dtype=float), axis, 0)
    flat = a.reshape(a.shape[0], -1)
    for k in range(flat.shape[1]):  # loop over columns, not frames
        ok = np.isfinite(flat[:, k])
        if ok.sum() > 1:
            flat[ok, k] = np.unwrap(flat[ok, k])
    return np.moveaxis(flat.reshape(a.shape), 0, axis)


def poses_to_coordinates(poses: SegmentPoses, *, unwrap: bool = True) -> np.ndarray:
    """Generalized coordinates (n, 27) in :data:`COORDINATES` order (3.1): metres and radians."""
    R = poses.rotation
    q = np.empty((poses.n_frames, len(COORDINATES)))
    q[:, 0:3] = poses.com_m[:, 0]
    q[:, 3:6] = matrix_to_cardan_xyz(R[:, 0])  # (3.16)
    for j, (p, c) in enumerate(zip(JOINT_PARENT, JOINT_CHILD)):
        relative = np.swapaxes(R[:, p], -1, -2) @ R[:, c]  # (3.17)
        q[:, 6 + 3 * j: 9 + 3 * j] = matrix_to_joint_angles(relative)  # (3.18)
    if unwrap:
        q[:, 3:] = unwrap_angles(q[:, 3:])
    return q


def missing_frame_messages(poses: SegmentPoses) -> list[str]:
    """One line per body with untracked frames, in file frame numbers (``first_frame`` based)."""
    lines = []
    for b, idx in poses.missing_frames.items():
        if len(idx):
            lines.append(f"segment {b} misses a tracking marker in frames {frame_spans(idx, poses.first_frame)}")
    return lines

