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

``c3d`` writes ``gait_out/export/<trial>.c3d``: a copy of the trial's C3D with Vicon's Plug-in Gait points added
per side — ``RPelvisAngles``, ``RHipAngles``, ``RKneeAngles``, ``RAnkleAngles``, ``RFootProgressAngles`` (deg),
``RHipMoment``, ``RKneeMoment``, ``RAnkleMoment`` (N·mm/kg) and ``RHipPower`` … (W/kg in Z), in Vicon's
components and signs (:func:`c3d_points`); POINT:ANGLES, POINT:MOMENTS, POINT:POWERS (the file's own lists
extended), their units and GAITCLI:CONVENTION (the convention idyn.h5 records for its shown moments) say so.
Points of these names the trial already holds (a Nexus trial's own Plug-in Gait outputs) are replaced, one label
each, and a warning names them. Moments and powers where the foot's load is unknown are invalid points. Its EVENT
group holds the gait events the filter used (the file's own or detected), as Vicon Nexus writes them ("Foot Strike"/
"Foot Off", "Left"/"Right"); the copy's text parameters are made writable
(:func:`gaitcli.io.c3d_write.add_points`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.errors import InputError
from gaitcli.io.atomic import atomic_path
from gaitcli.io.h5 import read_result
from gaitcli.io.opensim import write_motion, write_trc
from gaitcli.io.stage_files import IdynTables, read_idyn_tables

FORMATS = ("opensim", "c3d")
#: the files of ``export/opensim/``
OPENSIM_FILES = ("markers.trc", "coordinates.mot", "grf.mot", "joint_moments.sto", "external_loads.xml")
#: model axes (x forward, y left, z up) → OpenSim's (x forward, y up, z right)
TO_OPENSIM = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
C3D_JOINTS = (("hip", "Hip"), ("knee", "Knee"), ("ankle", "Ankle"))
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


def _trial(out_root: Path) -> Trial:
    return read_result(out_root / "filter" / "filter.h5", Trial, "trial", what="gait filter")


def export_opensim(out_root: Path) -> list[Path]:
    """``export/opensim/`` from ``out_root``'s filter and idyn outputs (module docstring)."""
    trial = _trial(out_root)
    idyn = read_idyn_tables(out_root / "idyn" / "idyn.h5")
    folder = out_root / "export" / "opensim"
    folder.mkdir(parents=True, exist_ok=True)
    markers = trial.markers
    written = [write_trc(folder / "markers.trc", markers.labels, 1000.0 * markers.positions_m @ TO_OPENSIM.T,
                         markers.rate_hz, first_frame=markers.first_frame)]
    time = idyn.time_s
    written.append(write_motion(folder / "coordinates.mot", {"time": time, **dict(zip(idyn.coordinates.columns,
                                                                                      idyn.coordinates.values.T))},
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
    moments = idyn.known_moments_Nm(idyn.coordinate_moments)
    written.append(write_motion(folder / "joint_moments.sto", {"time": time, **dict(zip(
        idyn.coordinate_moments.columns, moments.T))}, in_degrees=False, name="joint_moments"))
    with atomic_path(folder / "external_loads.xml") as tmp:
        tmp.write_text(EXTERNAL_LOADS.format(forces="\n".join(EXTERNAL_FORCE.format(side=s) for s in ("r", "l"))))
    return written + [folder / "external_loads.xml"]


def c3d_points(idyn: IdynTables) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """Vicon's Plug-in Gait points (frames, 3) and their descriptions, in Vicon's components and signs: angles
    (deg; AnkleAngles Y the tables' ankle inversion, the left pelvis mirrored), moments (N·mm/kg) and the
    total power in Z (W/kg); the 27 coordinates' angles where idyn ran with ``angles: posture``."""
    points, descriptions = {}, {}
    anatomical = "pelvis_tilt" in idyn.angles.columns
    column = {c: idyn.angles.values[:, k] for k, c in enumerate(idyn.angles.columns)}
    moments, powers = idyn.known_moments_Nm(), idyn.known_powers_W()
    for s, prefix in (("r", "R"), ("l", "L")):
        mirror = 1.0 if s == "r" else -1.0
        if anatomical:
            points[f"{prefix}PelvisAngles"] = np.column_stack([column["pelvis_tilt"],
                                                               mirror * column["pelvis_obliquity"],
                                                               mirror * column["pelvis_rotation"]])
            zero = np.zeros_like(column["pelvis_tilt"])
            points[f"{prefix}FootProgressAngles"] = np.column_stack([zero, zero, column[f"foot_{s}_progression"]])
            descriptions[f"{prefix}FootProgressAngles"] = "gaitcli foot progression (deg) in Z; X, Y not computed"
        for j, (joint, name) in enumerate(C3D_JOINTS):
            # the tables' ankle inversion is already Plug-in Gait's AnkleAngles Y (kinematics.conventions)
            second = "inversion" if anatomical and joint == "ankle" else "adduction"
            angles = [column[f"{joint}_{s}_{a}"] for a in ("flexion", second, "rotation")]
            k = 1 + j + (3 if s == "l" else 0)  # the joint's index in JOINTS
            points[f"{prefix}{name}Angles"] = np.column_stack(angles)
            points[f"{prefix}{name}Moment"] = 1000.0 * moments[:, 3 * k:3 * k + 3] / idyn.body_mass_kg
            power = np.zeros((len(idyn.time_s), 3))
            power[:, 2] = powers[:, k] / idyn.body_mass_kg
            points[f"{prefix}{name}Power"] = power
            descriptions[f"{prefix}{name}Angles"] = f"gaitcli {joint} angles (deg), Vicon's components and signs"
            descriptions[f"{prefix}{name}Moment"] = f"gaitcli {joint} moment (Nmm/kg), Plug-in Gait's signs"
            descriptions[f"{prefix}{name}Power"] = f"gaitcli {joint} power (W/kg) in Z"
    return points, descriptions


def export_c3d(out_root: Path, trial_c3d: Path) -> list[Path]:
    """``export/<trial>.c3d``: the trial's C3D with the angles and moments added (module docstring)."""
    from gaitcli.io.c3d_write import add_points

    if trial_c3d.suffix.lower() != ".c3d":
        raise InputError(trial_c3d, "--export", "c3d needs a C3D trial (this trial is a CSV)")
    idyn = read_idyn_tables(out_root / "idyn" / "idyn.h5")
    events = _trial(out_root).events
    points, descriptions = c3d_points(idyn)
    labels = list(points)
    target = out_root / "export" / f"{idyn.trial or trial_c3d.stem}.c3d"
    target.parent.mkdir(parents=True, exist_ok=True)
    parameters = {"POINT:ANGLES": [lab for lab in labels if lab.endswith("Angles")],
                  "POINT:MOMENTS": [lab for lab in labels if lab.endswith("Moment")],
                  "POINT:POWERS": [lab for lab in labels if lab.endswith("Power")],
                  "POINT:ANGLE_UNITS": "deg", "POINT:MOMENT_UNITS": "Nmm/kg", "POINT:POWER_UNITS": "W",
                  "GAITCLI:CONVENTION": idyn.moments.convention}
    return [add_points(trial_c3d, target, points, descriptions=descriptions, parameters=parameters,
                       events=events, merged=("POINT:ANGLES", "POINT:MOMENTS", "POINT:POWERS"))]


def export_targets(out_root: Path, formats, *, trial_name: str) -> list[Path]:
    """The files the exports ``formats`` of the trial (its folder's name) will write below ``out_root``: for
    checking their names before any stage runs (:func:`gaitcli.io.atomic.check_output_file`)."""
    targets = []
    if "opensim" in formats:
        targets += [out_root / "export" / "opensim" / name for name in OPENSIM_FILES]
    if "c3d" in formats:
        targets.append(out_root / "export" / f"{trial_name}.c3d")
    return targets


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
