"""Exports of a trial's idyn results for other tools: the model-free files (``gaitcli.run.exports`` assembles them
with the model's own, ``dynamics/opensim.py``).

For ``opensim`` (``gait_out/export/opensim/``): ``markers.trc`` (:func:`write_lab_markers`: the filtered markers,
mm, under the lab's own labels, without unlabelled and virtual points), ``grf.mot`` (:func:`write_ground_reactions`:
each foot's ground reaction in the column layout OpenSim's ExternalLoads read: ``r_ground_force_vx…vz``,
``r_ground_force_px…pz``, ``r_ground_torque_x…z``, and ``l_``) and ``external_loads.xml`` (the ExternalLoads set-up
that applies grf.mot to ``calcn_r`` and ``calcn_l``). OpenSim's axes are y up: a model-axes vector (x forward, y
left, z up) becomes (x, z, −y), so x stays forward and z points to the right. The free moment is about the
vertical (OpenSim's y). Where a foot's load is unknown (a stance off the plates) its force is what the plates gave
it (zero) and its point the origin: OpenSim cannot know either.

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

import re
from pathlib import Path

import numpy as np

from gaitcli.core.container import Trial
from gaitcli.errors import InputError
from gaitcli.io.atomic import atomic_path
from gaitcli.io.h5 import read_result
from gaitcli.io.opensim import write_motion, write_trc
from gaitcli.io.stage_files import IdynTables, read_idyn_tables

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


def filtered_trial(out_root: Path) -> Trial:
    """The filtered trial of an output root (``filter/filter.h5``)."""
    return read_result(out_root / "filter" / "filter.h5", Trial, "trial", what="gait filter")


#: Vicon's virtual points, which Plug-in Gait computes and a C3D stores beside the markers: each segment's origin,
#: anterior, lateral and proximal points (PELO, LFEA, RTOP, HEDL, …), joint centres and the centre of mass
VIRTUAL_POINT = re.compile(r"^(?:(?:PEL|HED|TRX|[LR](?:FE|TI|FO|TO|CL|HU|RA|HN))[OALP]|[LR]?[HKAESW]JC|"
                           r"CentreOfMass(?:Floor)?)$")


def marker_kind(label: str) -> str:
    """``unlabelled`` (Vicon's ``*115``: a trajectory nobody named), ``virtual`` (:data:`VIRTUAL_POINT`) or
    ``marker``."""
    if label.startswith("*"):
        return "unlabelled"
    return "virtual" if VIRTUAL_POINT.match(label) else "marker"


def lab_markers(trial: Trial) -> tuple[list[str], list[int], dict[str, list[str]]]:
    """The lab's labels of the trial's markers (as in the file: the marker set's renaming undone), the column of
    each in ``trial.markers``, and the labels left out by kind (``unlabelled``, ``virtual``). A lab marker that
    carries two landmarks (one SACR for both PSIS) is written once."""
    labels, columns, left_out = [], [], {"unlabelled": [], "virtual": []}
    for k, name in enumerate(trial.markers.labels):
        label = trial.marker_labels.get(name, name)
        kind = marker_kind(label)
        if kind != "marker":
            left_out[kind].append(label)
        elif label not in labels:
            labels.append(label)
            columns.append(k)
    return labels, columns, left_out


def write_lab_markers(path: Path, trial: Trial) -> tuple[Path, str | None]:
    """``markers.trc`` (:func:`lab_markers`, mm, OpenSim's axes) and one line naming what was left out (None when
    nothing was)."""
    markers = trial.markers
    labels, columns, left_out = lab_markers(trial)
    positions_mm = 1000.0 * markers.positions_m[:, columns] @ TO_OPENSIM.T
    written = write_trc(path, labels, positions_mm, markers.rate_hz, first_frame=markers.first_frame)
    parts = [f"{len(v)} {kind} ({_shortened(v)})" for kind, v in left_out.items() if v]
    return written, (f"{path.name}: {len(labels)} markers under the lab's labels; left out " + " and ".join(parts)
                     + " points") if parts else None


def _shortened(labels: list[str], shown: int = 4) -> str:
    return ", ".join(labels[:shown]) + (", …" if len(labels) > shown else "")


def write_ground_reactions(path: Path, trial: Trial, time_s: np.ndarray) -> Path:
    """``grf.mot``: each foot's force (N), point (m) and free moment (N·m) in OpenSim's axes and ExternalLoads'
    column names (module docstring)."""
    grf = {"time": time_s}
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
    return write_motion(path, grf, in_degrees=False, name="grf")


def write_external_loads(path: Path) -> Path:
    """``external_loads.xml``: grf.mot's two feet applied to ``calcn_r`` and ``calcn_l``."""
    with atomic_path(path) as tmp:
        tmp.write_text(EXTERNAL_LOADS.format(forces="\n".join(EXTERNAL_FORCE.format(side=s) for s in ("r", "l"))))
    return path


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
    events = filtered_trial(out_root).events
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
