"""Exports of a trial's idyn results for other tools (``gait idyn --export``, ``gait report --export``).

``opensim`` writes into ``gait_out/export/opensim/``: ``markers.trc`` (the filtered markers, mm), ``coordinates.mot``
(the 27 coordinates over time in the tables' clinical signs: angles in degrees, pelvis translations in m),
``grf.mot`` (each foot's ground reaction in the column layout OpenSim's ExternalLoads read:
``r_ground_force_vx…vz``, ``r_ground_force_px…pz``, ``r_ground_torque_x…z``, and ``l_``), ``joint_moments.sto``
(the 21 joint moments, N·m, NaN where the foot's load is unknown) and ``external_loads.xml`` (the ExternalLoads
set-up that applies grf.mot to ``calcn_r`` and ``calcn_l``). OpenSim's axes are y up: a model-axes vector (x
forward, y left, z up) becomes (x, z, −y), so x stays forward and z points to the right. The free moment is
about the vertical (OpenSim's y). Where a foot's load is unknown (a stance off the plates) its force is what the
plates gave it (zero) and its point the origin: OpenSim cannot know either.

``c3d`` writes ``gait_out/export/<trial>.c3d``: a copy of the trial's C3D with Plug-in Gait-style points added
per side — ``RHipAngles``, ``RKneeAngles``, ``RAnkleAngles`` (deg) and ``RHipMoment``, ``RKneeMoment``,
``RAnkleMoment`` (N·mm/kg, as Vicon writes them), components (flexion, adduction, rotation) in the tables'
clinical signs (flexion, dorsiflexion, adduction, internal rotation and each moment in the sense of its angle
positive, both sides alike); POINT:ANGLES, POINT:MOMENTS, POINT:ANGLE_UNITS, POINT:MOMENT_UNITS and
GAITCLI:CONVENTION say so. Moments where the foot's load is unknown are invalid points.
"""

from __future__ import annotations

from pathlib import Path

import h5py
import numpy as np

from gaitcli.core.container import Trial
from gaitcli.errors import InputError
from gaitcli.io.atomic import atomic_path
from gaitcli.io.h5 import read_record
from gaitcli.io.opensim import write_motion, write_trc

FORMATS = ("opensim", "c3d")
#: model axes (x forward, y left, z up) → OpenSim's (x forward, y up, z right)
TO_OPENSIM = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
C3D_JOINTS = (("hip", "Hip"), ("knee", "Knee"), ("ankle", "Ankle"))
CONVENTION = ("clinical: hip/knee flexion, ankle dorsiflexion, adduction and internal rotation positive on both "
              "sides; components (flexion, adduction, rotation); moments (internal, of the proximal on the distal "
              "segment) positive in the sense of their angle")
EXTERNAL_LOADS = """<?xml version="1.0" encoding="UTF-8" ?>
<OpenSimDocument Version="40000">
  <ExternalLoads name="gaitcli_external_loads">
    <objects>
{forces}
    </objects>
    <datafile>grf.mot</datafile>
  </ExternalLoads>
</OpenSimDocument>
"""
EXTERNAL_FORCE = """      <ExternalForce name="{side}_foot">
        <applied_to_body>calcn_{side}</applied_to_body>
        <force_expressed_in_body>ground</force_expressed_in_body>
        <point_expressed_in_body>ground</point_expressed_in_body>
        <force_identifier>{side}_ground_force_v</force_identifier>
        <point_identifier>{side}_ground_force_p</point_identifier>
        <torque_identifier>{side}_ground_torque_</torque_identifier>
        <data_source_name>grf.mot</data_source_name>
      </ExternalForce>"""


def _idyn(folder: Path) -> dict:
    with h5py.File(folder / "idyn.h5", "r") as h5:
        out = {"time": h5["time"][()], "q": h5["coordinates_clinical"][()],
               "q_columns": str(h5["coordinates_clinical"].attrs["columns"]).split(","),
               "moments": h5["joint_moments_clinical"][()],
               "moment_columns": str(h5["joint_moments_clinical"].attrs["columns"]).split(","),
               "known": h5["joint_moments_known"][()].astype(bool),
               "mass_kg": float(h5["segments/mass"].attrs["body_mass_kg"]), "trial": str(h5.attrs.get("trial", ""))}
    out["moments"] = np.where(np.repeat(out["known"], 3, axis=1), out["moments"], np.nan)
    return out


def export_opensim(out_root: Path) -> list[Path]:
    """``export/opensim/`` from ``out_root``'s filter and idyn outputs (module docstring)."""
    with h5py.File(out_root / "filter" / "filter.h5", "r") as h5:
        trial = read_record(h5["trial"], Trial)
    idyn = _idyn(out_root / "idyn")
    folder = out_root / "export" / "opensim"
    folder.mkdir(parents=True, exist_ok=True)
    markers = trial.markers
    written = [write_trc(folder / "markers.trc", markers.labels, 1000.0 * markers.positions_m @ TO_OPENSIM.T,
                         markers.rate_hz, first_frame=markers.first_frame)]
    time = idyn["time"]
    written.append(write_motion(folder / "coordinates.mot", {"time": time, **dict(zip(idyn["q_columns"],
                                                                                      idyn["q"].T))},
                                in_degrees=True, name="coordinates"))
    grf = {"time": time}
    for s in ("r", "l"):
        foot = trial.feet[s]
        force = np.nan_to_num(foot.force_N) @ TO_OPENSIM.T
        point = np.nan_to_num(foot.cop_m) @ TO_OPENSIM.T
        torque = np.zeros_like(force)
        torque[:, 1] = np.nan_to_num(foot.free_moment_Nm)  # about the vertical: OpenSim's y
        for k, a in enumerate("xyz"):
            grf[f"{s}_ground_force_v{a}"] = force[:, k]
        for k, a in enumerate("xyz"):
            grf[f"{s}_ground_force_p{a}"] = point[:, k]
        for k, a in enumerate("xyz"):
            grf[f"{s}_ground_torque_{a}"] = torque[:, k]
    written.append(write_motion(folder / "grf.mot", grf, in_degrees=False, name="grf"))
    written.append(write_motion(folder / "joint_moments.sto", {"time": time, **dict(zip(idyn["moment_columns"],
                                                                                        idyn["moments"].T))},
                                in_degrees=False, name="joint_moments"))
    with atomic_path(folder / "external_loads.xml") as tmp:
        tmp.write_text(EXTERNAL_LOADS.format(forces="\n".join(EXTERNAL_FORCE.format(side=s) for s in ("r", "l"))))
    return written + [folder / "external_loads.xml"]


def c3d_points(idyn: dict) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The Plug-in Gait-style points (frames, 3) and their descriptions from idyn's clinical tables."""
    points, descriptions = {}, {}
    for s, prefix in (("r", "R"), ("l", "L")):
        for joint, name in C3D_JOINTS:
            angles = [idyn["q"][:, idyn["q_columns"].index(f"{joint}_{s}_{a}")] for a in
                      ("flexion", "adduction", "rotation")]
            moments = [idyn["moments"][:, idyn["moment_columns"].index(f"{joint}_{s}_{a}_moment")] for a in
                       ("flexion", "adduction", "rotation")]
            points[f"{prefix}{name}Angles"] = np.column_stack(angles)
            points[f"{prefix}{name}Moment"] = 1000.0 * np.column_stack(moments) / idyn["mass_kg"]
            descriptions[f"{prefix}{name}Angles"] = f"gaitcli {joint} angles (deg), clinical signs"
            descriptions[f"{prefix}{name}Moment"] = f"gaitcli {joint} moment (Nmm/kg), clinical signs"
    return points, descriptions


def export_c3d(out_root: Path, trial_c3d: Path) -> list[Path]:
    """``export/<trial>.c3d``: the trial's C3D with the angles and moments added (module docstring)."""
    from gaitcli.io.c3d_write import add_points

    if trial_c3d.suffix.lower() != ".c3d":
        raise InputError(trial_c3d, "--export", "c3d needs a C3D trial (this trial is a CSV)")
    idyn = _idyn(out_root / "idyn")
    points, descriptions = c3d_points(idyn)
    labels = list(points)
    target = out_root / "export" / f"{idyn['trial'] or trial_c3d.stem}.c3d"
    target.parent.mkdir(parents=True, exist_ok=True)
    parameters = {"POINT:ANGLES": [lab for lab in labels if lab.endswith("Angles")],
                  "POINT:MOMENTS": [lab for lab in labels if lab.endswith("Moment")],
                  "POINT:ANGLE_UNITS": "deg", "POINT:MOMENT_UNITS": "Nmm/kg", "GAITCLI:CONVENTION": CONVENTION}
    return [add_points(trial_c3d, target, points, descriptions=descriptions, parameters=parameters)]


def export_trial(out_root: Path, formats, *, trial_c3d: Path | None = None) -> list[Path]:
    """Every export in ``formats`` (``opensim``, ``c3d``) of a trial output root."""
    written = []
    if "opensim" in formats:
        written += export_opensim(out_root)
    if "c3d" in formats:
        if trial_c3d is None:
            raise InputError(out_root, "--export", "c3d needs the trial's C3D file")
        written += export_c3d(out_root, trial_c3d)
    return written
