"""What a lab puts on a synthetic subject besides its markers: a knee alignment device in the static trial."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from gaitcli.core.recording import Markers

#: m: a knee alignment device's arms, hub to marker
KAD_ARM_M = 0.08


def with_knee_alignment_device(static: Markers, knee_centres_m: Mapping[str, np.ndarray], *,
                               arm_m: float = KAD_ARM_M) -> Markers:
    """``static`` with a knee alignment device in place of each knee marker (RKNE, LKNE): its hub where the knee
    marker was, KAX ``arm_m`` along the knee axis (laterally: the knee centre ``knee_centres_m["KJCr"]`` /
    ``["KJCl"]`` (3,) or (frames, 3), m, towards the knee marker), KD1 and KD2 on the two arms orthogonal to it;
    no knee marker."""
    pos, labels = static.positions_m, list(static.labels)
    columns = {lab: pos[:, i] for i, lab in enumerate(labels) if lab not in ("RKNE", "LKNE")}
    for side, prefix in (("r", "R"), ("l", "L")):
        hub = pos[:, labels.index(f"{prefix}KNE")]
        axis = hub - knee_centres_m[f"KJC{side}"]
        axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
        b = np.cross(axis, [0.0, 0.0, 1.0])
        b /= np.linalg.norm(b, axis=-1, keepdims=True)
        b = np.cos(0.6) * b + np.sin(0.6) * np.cross(axis, b)  # the arms turned off the vertical, as worn
        for name, direction in (("KAX", axis), ("KD1", b), ("KD2", np.cross(axis, b))):
            columns[f"{prefix}{name}"] = hub + arm_m * direction
    return Markers(tuple(columns), np.stack(list(columns.values()), axis=1), static.rate_hz, static.first_frame)
