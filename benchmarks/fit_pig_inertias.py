"""Which leg segment parameters Vicon Nexus's Plug-in Gait kinetics use, measured on its own outputs.

Run from the repository root: ``python benchmarks/fit_pig_inertias.py [--shared PATH]``. Prints; asserts nothing.

1. **The thigh from Vicon's own chain.** ``../shared/data/pig/Movement_trial.c3d`` holds, per frame, Vicon's femur
   and tibia frames (``RFEO``/``RFEA``/``RFEL``/``RFEP``: origin at the knee centre, anterior, lateral and
   proximal points, ``RFEP`` the hip centre) and its knee and hip loads (``RKneeForce`` N/kg and ``RKneeMoment``
   N·mm/kg in the tibia frame, ``RHipMoment`` in the femur frame; a moment's X about the segment's lateral axis, Y
   about its anterior axis, Z about its long axis). Newton–Euler on the thigh alone turns Vicon's knee loads into
   a hip moment given the thigh's mass m, CoM (a fraction c of the length from the hip centre) and inertia; the
   frames are differentiated twice (central differences) for its angular velocity and acceleration. Printed: the
   RMS of that hip moment against Vicon's (every frame, N·m/kg) for de Leva's thigh, Dempster's (radius of gyration
   0.323 about the CoM) and Plug-in Gait's (``PLUG_IN_GAIT_LEGS``: 0.54), and the radius that fits best.
2. **Shank and foot through gaitcli.** The session through ``gait idyn`` with the shank's and the foot's radius of
   gyration set in turn to Dempster's values about the CoM (0.302, 0.475) and about the proximal end (0.528,
   0.690): RMS and slope of the right knee and ankle moments against Vicon's in stance (Vicon's ground reaction on
   that foot) and in swing (no load on it in either; the right foot's frames 160–260 on an unassigned plate left
   out). The left foot's swing steps on stairs off the plates and is not compared.
"""

from __future__ import annotations

import argparse
import dataclasses
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np
from bench_pig import ROOT, SUBJECT, read_csv, vicon_points

from gaitcli import api
from gaitcli.kinematics import anthropometry

RATE_HZ = 120.0
GRAVITY = np.array([0.0, 0.0, -9.81])
#: Vicon's moment components (X, Y, Z) as components along its frames' (anterior, lateral, proximal) axes
AXIS_OF_COMPONENT = [1, 0, 2]
#: signs turning Vicon's components into moments of the proximal on the distal segment, per side and joint
SIGNS = {("R", "Knee"): (-1, -1, -1), ("R", "Hip"): (1, -1, -1), ("L", "Knee"): (-1, 1, 1), ("L", "Hip"): (1, 1, 1)}


def frame(points: dict, name: str) -> tuple[np.ndarray, np.ndarray]:
    """Vicon's segment frame ``name`` (``RFE``…): origin (n, 3) m and rotation (n, 3, 3), columns anterior, lateral,
    proximal."""
    origin = points[name + "O"] / 1000.0
    axes = [points[name + c] / 1000.0 - origin for c in "ALP"]
    return origin, np.stack([a / np.linalg.norm(a, axis=1, keepdims=True) for a in axes], axis=2)


def moment_in_lab(points: dict, side: str, joint: str, rotation: np.ndarray) -> np.ndarray:
    """Vicon's ``{side}{joint}Moment`` as a vector in the lab (N·m/kg), the moment of the proximal on the distal."""
    local = (points[f"{side}{joint}Moment"] * np.array(SIGNS[side, joint]))[:, AXIS_OF_COMPONENT] / 1000.0
    return np.einsum("nij,nj->ni", rotation, local)


def thigh_hip_moment(points: dict, side: str, mass: float, com_from_hip: float, radius: float) -> np.ndarray:
    """The hip moment (lab, N·m/kg) Newton–Euler gives on Vicon's thigh from Vicon's knee loads, for a thigh of
    ``mass`` (fraction of body mass), CoM ``com_from_hip`` and transverse ``radius`` (fractions of its length)."""
    dt = 1.0 / RATE_HZ
    knee, femur = frame(points, side + "FE")
    _, tibia = frame(points, side + "TI")
    hip = points[side + "FEP"] / 1000.0
    knee_moment = moment_in_lab(points, side, "Knee", tibia)
    knee_force = np.einsum("nij,nj->ni", tibia, points[side + "KneeForce"])  # on the shank, from the thigh
    spin = np.einsum("nij,nkj->nik", np.gradient(femur, dt, axis=0), femur)
    omega = np.stack([spin[:, 2, 1], spin[:, 0, 2], spin[:, 1, 0]], axis=1)
    alpha = np.gradient(omega, dt, axis=0)
    length = np.linalg.norm(hip - knee, axis=1)
    com = hip + com_from_hip * (knee - hip)
    accel = np.gradient(np.gradient(com, dt, axis=0), dt, axis=0)
    inertia = np.einsum("nij,j,nkj->nik", femur, [1.0, 1.0, 0.0], femur) * (mass * (radius * length) ** 2)[:, None,
                                                                                                          None]
    euler = np.einsum("nij,nj->ni", inertia, alpha) + np.cross(omega, np.einsum("nij,nj->ni", inertia, omega))
    return (euler + np.cross(com - hip, mass * (accel - GRAVITY)) + knee_moment
            + np.cross(knee - hip, knee_force))


def thigh_rms(points: dict, side: str, *params) -> float:
    _, femur = frame(points, side + "FE")
    diff = thigh_hip_moment(points, side, *params) - moment_in_lab(points, side, "Hip", femur)
    ok = np.isfinite(diff).all(axis=1)
    return float(np.sqrt(np.mean(diff[ok] ** 2)))


def shank_and_foot(shared: Path, points: dict, variants: list[tuple[float, float]]) -> None:
    """Part 2: each (shank radius, foot radius) through ``gait idyn`` in this process."""
    base = dict(anthropometry.PLUG_IN_GAIT_LEGS)
    loaded = np.nan_to_num(points["RGroundReactionForce"][:, 2]) > 0.5
    print("\nshank / foot radius   right knee stance, swing (RMS N·m/kg, slope)   right ankle stance, swing")
    for shank, foot in variants:
        anthropometry.PLUG_IN_GAIT_LEGS.update(shank=dataclasses.replace(base["shank"], radius_pct=shank),
                                              foot=dataclasses.replace(base["foot"], radius_pct=foot))
        root = Path(tempfile.mkdtemp(prefix="fit_pig_"))
        try:
            for name, target in (("Movement_trial.c3d", "trial.c3d"), ("Static_trial.c3d", "static.c3d"),
                                 ("Test.vsk", "Test.vsk")):
                shutil.copy(shared / name, root / target)
            (root / "subject.yaml").write_text(SUBJECT)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                api.run_trial(root, stages=["filter", "idyn"])
            moments = read_csv(root / "gait_out" / "idyn" / "joint_moments.csv")
            load = read_csv(root / "gait_out" / "filter" / "grf.csv")["foot_r_force_z_N"]
        finally:
            shutil.rmtree(root, ignore_errors=True)
        swing = (np.nan_to_num(load) == 0) & ~loaded & (np.arange(load.size) < 160)
        swing |= (np.nan_to_num(load) == 0) & ~loaded & (np.arange(load.size) > 260)
        cells = []
        for column, label in (("knee_r_extensor_moment_per_kg", "RKneeMoment"),
                              ("ankle_r_plantarflexor_moment_per_kg", "RAnkleMoment")):
            ours, theirs = moments[column], points[label][:, 0] / 1000.0
            for mask in (loaded, swing):
                ok = mask & np.isfinite(ours) & np.isfinite(theirs)
                rms = np.sqrt(np.mean((ours[ok] - theirs[ok]) ** 2))
                cells.append(f"{rms:.3f} {np.polyfit(theirs[ok], ours[ok], 1)[0]:5.2f}")
        print(f"{shank:5.1f} / {foot:5.1f}          " + "   ".join(cells))
    anthropometry.PLUG_IN_GAIT_LEGS.update(base)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=ROOT.parent / "shared" / "data" / "pig")
    args = parser.parse_args()
    if not (args.shared / "Movement_trial.c3d").exists():
        sys.exit(f"no Plug-in Gait session at {args.shared}")
    points = vicon_points(args.shared / "Movement_trial.c3d")
    print("thigh: Vicon's hip moment from Vicon's knee loads and frames (RMS N·m/kg over every frame)")
    pig = anthropometry.PLUG_IN_GAIT_LEGS["thigh"]
    tables = {"de Leva (male)": (0.1416, 0.4095, 0.329), "Dempster, radius about the CoM": (0.100, 0.433, 0.323),
              "Plug-in Gait (PLUG_IN_GAIT_LEGS)": (pig.mass_pct / 100, pig.com_pct / 100, pig.radius_pct / 100)}
    for side in "RL":
        row = "  ".join(f"{name} {thigh_rms(points, side, *p):.4f}" for name, p in tables.items())
        radii = np.arange(0.30, 0.70, 0.005)
        best = radii[np.argmin([thigh_rms(points, side, 0.100, 0.433, r) for r in radii])]
        print(f"{side}: {row}  best radius (Dempster's mass and CoM) {best:.3f}")
    shank_and_foot(args.shared, points, [(30.2, 47.5), (52.8, 47.5), (30.2, 69.0), (52.8, 69.0)])


if __name__ == "__main__":
    main()
