"""The Gait Profile Score and Gait Variable Scores (Baker et al. 2009, Gait & Posture 30:265–269): how far a
person's mean kinematics over the cycle lie from a normal band's mean, in degrees.

A Gait Variable Score is the root mean square, over the points of the cycle (0–100 %, :data:`CYCLE_PCT`), of
the difference between one kinematic variable's mean curve and the band's mean of it. The Gait Profile Score
is the root mean square of the GVS: per side over that side's variables, and overall over every variable of
both sides. Baker's nine variables per side are the pelvis's tilt, obliquity and rotation, the hip's flexion,
abduction and rotation, knee flexion, ankle dorsiflexion and foot progression, the pelvis as each side's cycle
reports it (gait_cycle.csv mirrors the left's obliquity and rotation); a band without some of them gives a GPS
over the others, and the result says which it used.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gaitcli.signal.bands import Band

#: Baker's variables of one side: (gait_cycle.csv column with {s} for the side, band variable)
GPS_VARIABLES = (("pelvis_tilt", "pelvis_tilt_deg"), ("pelvis_obliquity", "pelvis_obliquity_deg"),
                 ("pelvis_rotation", "pelvis_rotation_deg"), ("hip_{s}_flexion", "hip_flexion_deg"),
                 ("hip_{s}_adduction", "hip_adduction_deg"), ("hip_{s}_rotation", "hip_rotation_deg"),
                 ("knee_{s}_flexion", "knee_flexion_deg"), ("ankle_{s}_flexion", "ankle_flexion_deg"),
                 ("foot_{s}_progression", "foot_progression_deg"))


@dataclass(frozen=True)
class GaitProfile:
    """GVS {(side, column): degrees}, the GPS per side and overall (degrees), and the variables used."""

    gvs: dict[tuple[str, str], float]
    gps_side: dict[str, float]
    gps: float

    def as_dict(self) -> dict:
        """summary.json's block: ``gps_deg``, ``gps_right_deg``, ``gps_left_deg`` and ``gvs_deg`` per side
        ({"right": {column: degrees}, "left": …})."""
        sides = {"r": "right", "l": "left"}
        return {"gps_deg": self.gps, **{f"gps_{sides[s]}_deg": v for s, v in self.gps_side.items()},
                "gvs_deg": {sides[side]: {c: v for (s, c), v in self.gvs.items() if s == side}
                            for side in self.gps_side}}


def gait_variable_score(curve: np.ndarray, normal: np.ndarray) -> float:
    """RMS difference (same units) of a mean curve and the band's mean over the cycle's points (NaN-free)."""
    difference = np.asarray(curve, float) - np.asarray(normal, float)
    return float(np.sqrt(np.mean(difference ** 2)))


def gait_profile(means: dict[str, dict[str, np.ndarray]], band: Band) -> GaitProfile:
    """GVS and GPS of each side's mean curves ``means[side][column]`` (101 points, degrees; e.g. a session's
    cycle.csv) against ``band``; a variable the band or the curves lack (or hold NaN in) is left out. The
    pelvis counts once overall, from the left side's cycle (Baker et al.)."""
    gvs: dict[tuple[str, str], float] = {}
    for side, curves in means.items():
        for pattern, variable in GPS_VARIABLES:
            column = pattern.format(s=side)
            normal = band.get(variable)
            if normal is None or column not in curves or not np.all(np.isfinite(curves[column])):
                continue
            gvs[(side, column)] = gait_variable_score(curves[column], normal[0])
    if not gvs:
        raise ValueError("no kinematic variable of the Gait Profile Score in both the curves and the band")
    per_side = {side: float(np.sqrt(np.mean([v ** 2 for (s, _), v in gvs.items() if s == side])))
                for side in means if any(s == side for s, _ in gvs)}
    pelvis_side = "l" if any(s == "l" and c.startswith("pelvis") for s, c in gvs) else "r"
    overall = [v for (s, c), v in gvs.items() if not c.startswith("pelvis") or s == pelvis_side]
    return GaitProfile(gvs, per_side, float(np.sqrt(np.mean(np.square(overall)))))
