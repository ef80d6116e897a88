"""The exports of a trial's idyn results for other tools (``gait idyn --export``, ``gait report --export``).

``opensim`` writes ``gait_out/export/opensim/`` (docs/opensim.md): ``model.osim``, the subject's calibrated 8-body,
27-coordinate model (:func:`gaitcli.dynamics.opensim.osim_model`); ``markers.trc``, the filtered markers under the
lab's labels (:func:`gaitcli.io.exports.write_lab_markers`); ``coordinates.mot``, the 27 coordinates under OpenSim's
names and in its senses (deg; pelvis translations m); ``grf.mot`` and ``external_loads.xml``, the ground reactions
on ``calcn_r``/``calcn_l``; ``joint_moments.sto``, the 27 generalized forces as OpenSim's InverseDynamicsTool names
them (``hip_flexion_r_moment`` N·m, ``pelvis_tx_force`` N), NaN where the load they depend on is unknown (a leg's
where its foot's is; the pelvis's where any foot's is). OpenSim's inverse dynamics on model.osim, coordinates.mot
and external_loads.xml gives joint_moments.sto (tests/cli/test_export_cli.py, test_export_real.py).

``c3d`` writes ``gait_out/export/<trial>.c3d`` (:func:`gaitcli.io.exports.export_c3d`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.dynamics.opensim import generalized_forces, opensim_coordinates, opensim_generalized_forces, osim_model
from gaitcli.errors import InputError
from gaitcli.io.atomic import atomic_path
from gaitcli.io.exports import (
    export_c3d,
    filtered_trial,
    write_external_loads,
    write_ground_reactions,
    write_lab_markers,
)
from gaitcli.io.opensim import write_motion
from gaitcli.io.stage_files import read_idyn_model
from gaitcli.kinematics.model import BodyParameters

FORMATS = ("opensim", "c3d")
#: the files of ``export/opensim/``
OPENSIM_FILES = ("model.osim", "markers.trc", "coordinates.mot", "grf.mot", "joint_moments.sto",
                 "external_loads.xml")


def body_parameters(model) -> BodyParameters:
    """The calibrated bodies of an :class:`~gaitcli.io.stage_files.IdynModel`."""
    return BodyParameters(model.mass_kg, model.inertia_kgm2, model.joint_in_parent_m, model.joint_in_child_m)


def known_generalized_forces(model) -> np.ndarray:
    """The 27 generalized forces (frames, 27) of an :class:`~gaitcli.io.stage_files.IdynModel` (3.19), NaN where
    their load is unknown: the pelvis's six where any contact's is, a joint's three where its own is."""
    forces = generalized_forces(model.q, body_parameters(model), model.joint_moments_global_Nm, model.residual_force_N,
                                model.residual_moment_Nm)
    known = np.column_stack([np.repeat(model.all_contacts_measured[:, None], 6, axis=1),
                             np.repeat(model.moment_known, 3, axis=1)])
    return np.where(known, forces, np.nan)


def export_opensim(out_root: Path) -> tuple[list[Path], list[str]]:
    """``export/opensim/`` from ``out_root``'s filter and idyn outputs (module docstring): the files written and
    what the command says about them (the points the .trc leaves out)."""
    trial = filtered_trial(out_root)
    model = read_idyn_model(out_root / "idyn" / "idyn.h5")
    folder = out_root / "export" / "opensim"
    folder.mkdir(parents=True, exist_ok=True)
    with atomic_path(folder / "model.osim") as tmp:
        tmp.write_text(osim_model(body_parameters(model), name=f"gaitcli_{model.trial or 'trial'}",
                                  gravity_m_s2=model.gravity_m_s2))
    trc, note = write_lab_markers(folder / "markers.trc", trial)
    time = model.time_s
    written = [folder / "model.osim", trc,
               write_motion(folder / "coordinates.mot", {"time": time, **opensim_coordinates(model.q)},
                            in_degrees=True, name="coordinates"),
               write_ground_reactions(folder / "grf.mot", trial, time),
               write_motion(folder / "joint_moments.sto",
                            {"time": time, **opensim_generalized_forces(known_generalized_forces(model))},
                            in_degrees=False, name="inverse_dynamics"),
               write_external_loads(folder / "external_loads.xml")]
    return written, [note] if note else []


def export_targets(out_root: Path, formats, *, trial_name: str) -> list[Path]:
    """The files the exports ``formats`` of the trial (its folder's name) will write below ``out_root``: for
    checking their names before any stage runs (:func:`gaitcli.io.atomic.check_output_file`)."""
    targets = []
    if "opensim" in formats:
        targets += [out_root / "export" / "opensim" / name for name in OPENSIM_FILES]
    if "c3d" in formats:
        targets.append(out_root / "export" / f"{trial_name}.c3d")
    return targets


def export_trial(out_root: Path, formats, *, trial_c3d: Path | None = None) -> tuple[list[Path], list[str]]:
    """Every export in ``formats`` (``opensim``, ``c3d``) of a trial output root: the files written and the lines
    the command prints about them."""
    written, notes = [], []
    if "opensim" in formats:
        files, notes = export_opensim(out_root)
        written += files
    if "c3d" in formats:
        if trial_c3d is None:
            raise InputError(out_root, "--export", "c3d needs the trial's C3D file")
        written += export_c3d(out_root, trial_c3d)
    return written, notes
