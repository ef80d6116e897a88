"""Which feet stood on which force plate when, in every real trial with plates in ``../shared/data``, found
without gaitcli: ezc3d's plate outlines and vertical force, and each file's heel and toe markers in lab axes.

A foot marker stands on a plate in a frame when it is over the plate's outline, at most 110 mm above the plate's
top (a heel marker sits 30-90 mm above the sole; this keeps out a foot on the step above a stair plate), moves
slower than 0.6 m/s horizontally (a foot swinging over a plate is faster) and the plate's vertical force is above
20 N (sampled at the marker frames). Prints per file its EVENT group where it has one, then per loaded plate the
loaded frames and, per foot, the frames its heel and its toe stood on it, and the frames both feet did. Frames are
the file's own (1-based, from its first frame). The findings are in docs/plates_real.md.
Run: ``python benchmarks/survey_plates.py [DATA_DIR]`` (default ``../shared/data``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import ezc3d
import numpy as np

#: file → heel, toe labels of the right foot, then of the left
FEET = {
    "c3d/walking2.c3d": (["RCAL"], ["RMT1", "RMT2"], ["LCAL"], ["LMT1", "LMT2"]),
    "c3d/walking5.c3d": (["RCAL"], ["RMT1", "RMT2"], ["LCAL"], ["LMT1", "LMT2"]),
    "c3d/Qualisys.c3d": (["R_FCC"], ["R_FM1", "R_FM5"], ["L_FCC"], ["L_FM1", "L_FM5"]),
    "c3d/Eb015pr.c3d": (["RFT3"], ["RFT1", "RFT2"], ["LFT3"], ["LFT1", "LFT2"]),  # foot clusters only
    "c3d/BTS.c3d": (["r heel"], ["r met"], ["l heel"], ["l met"]),
    "pig/Movement_trial.c3d": (["RHEE"], ["RTOE"], ["LHEE"], ["LTOE"]),
    "emg/Gait.c3d": (["RHEE"], ["RTOE"], ["LHEE"], ["LTOE"]),
}
THRESHOLD_N, ABOVE_TOP_MM, SLOW_M_S = 20.0, 110.0, 0.6


def inside(points: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """Whether each 2-D point (n, 2) lies inside the convex outline ``corners`` (4, 2)."""
    edges = np.roll(corners, -1, 0) - corners
    area2 = np.sum(corners[:, 0] * np.roll(corners[:, 1], -1) - np.roll(corners[:, 0], -1) * corners[:, 1])
    cross = (edges[None, :, 0] * (points[:, None, 1] - corners[None, :, 1])
             - edges[None, :, 1] * (points[:, None, 0] - corners[None, :, 0]))
    return np.all(np.sign(area2) * cross >= 0, axis=1)


def spans(mask: np.ndarray, first: int) -> str:
    idx = np.flatnonzero(mask)
    if not idx.size:
        return "-"
    breaks = np.flatnonzero(np.diff(idx) > 1)
    return ", ".join(f"{a + first}–{b + first}" for a, b in zip(np.r_[idx[0], idx[breaks + 1]],
                                                                  np.r_[idx[breaks], idx[-1]]))


def survey(path: Path, labels_of_feet) -> None:
    c = ezc3d.c3d(str(path), extract_forceplat_data=True)
    p = c["parameters"]
    labels = [lab.strip() for lab in p["POINT"]["LABELS"]["value"]]
    points = c["data"]["points"][:3]
    rate = float(p["POINT"]["RATE"]["value"][0])
    first = int(c["header"]["points"]["first_frame"]) + 1
    n = points.shape[2]
    scale = 1000.0 if p["POINT"]["UNITS"]["value"][0].strip() == "m" else 1.0
    up = int(np.argmin(np.ptp(np.asarray(c["data"]["platform"][0]["corners"], float), axis=1)))  # plate normal
    across = [k for k in range(3) if k != up]
    print(f"=== {path.name}: {n} frames at {rate:g} Hz from frame {first}")
    event = p.get("EVENT", {})
    if event and int(event["USED"]["value"][0]):
        names = event["LABELS"]["value"]
        contexts = event.get("CONTEXTS", {}).get("value", [""] * len(names))
        times = event["TIMES"]["value"]
        listed = sorted(zip(60 * times[0] + times[1], contexts, names))
        print("  EVENT: " + "; ".join(f"{cx} {nm} frame {round(t * rate) + 1}" for t, cx, nm in listed))

    def markers(names):
        out = []
        for name in names:
            if name in labels and labels.index(name) < points.shape[1]:
                x = points[:, labels.index(name), :].T * scale
                x[np.all(x == 0, axis=1)] = np.nan
                out.append(x)
        return out

    feet = {"right": (markers(labels_of_feet[0]), markers(labels_of_feet[1])),
            "left": (markers(labels_of_feet[2]), markers(labels_of_feet[3]))}
    for k, plate in enumerate(c["data"]["platform"]):
        corners = np.asarray(plate["corners"], float)
        step = plate["force"].shape[1] // n
        fz = np.asarray(plate["force"], float)[up, ::step][:n]
        loaded = np.abs(fz) > THRESHOLD_N
        if not loaded.any():
            continue
        top = float(np.mean(corners[up]))
        starts = np.flatnonzero(np.diff(np.r_[0, loaded.astype(int), 0]) == 1)
        stops = np.flatnonzero(np.diff(np.r_[0, loaded.astype(int), 0]) == -1)
        long = (stops - starts) >= 0.1 * rate
        lasting = np.zeros(n, bool)
        for a, b in zip(starts[long], stops[long]):
            lasting[a:b] = True
        noise = f" (and {int((loaded & ~lasting).sum())} frames of noise above {THRESHOLD_N:g} N)" \
            if (loaded & ~lasting).any() else ""
        print(f"  plate{k + 1} (top at {top:.0f} mm): loaded {spans(lasting, first)}{noise}")
        on_feet = {}
        for side, (heels, toes) in feet.items():
            found, on_foot = [], np.zeros(n, bool)
            for kind, group in (("heel", heels), ("toe", toes)):
                on = np.zeros(n, bool)
                for x in group:
                    speed = np.linalg.norm(np.gradient(x[:, across], axis=0), axis=1) * rate / 1000.0
                    with np.errstate(invalid="ignore"):
                        on |= (inside(x[:, across], corners[across].T) & (x[:, up] - top <= ABOVE_TOP_MM)
                               & (x[:, up] - top >= -30) & (speed < SLOW_M_S) & loaded)
                found.append(f"{kind} {spans(on, first)}")
                on_foot |= on
            on_feet[side] = on_foot
            print(f"    {side}: " + "; ".join(found))
        print(f"    both feet: {spans(on_feet['right'] & on_feet['left'], first)}")


if __name__ == "__main__":
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared" / "data"
    for name, labels_of_feet in FEET.items():
        if (root / name).is_file():
            survey(root / name, labels_of_feet)
