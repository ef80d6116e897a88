"""Writes the idyn stage's files: kinematics.csv, joint_moments.csv, residuals.csv, sagittal.csv,
gait_cycle.csv and idyn.h5, and gives its summary; reads ``idyn.h5`` back typed (:func:`read_idyn_output`)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.dynamics.sagittal import SagittalExport, sagittal_columns
from gaitcli.dynamics.stage import IdynResult
from gaitcli.io.h5 import Dataset, read_result, record_datasets, write_h5
from gaitcli.io.outputs import write_table
from gaitcli.io.stage_files import IdynTables, read_idyn_tables
from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES, MIRRORED_ON_LEFT
from gaitcli.kinematics.conventions import (
    ANATOMICAL_CONVENTION,
    CONVENTION,
    PIG_CONVENTION,
    PIG_MOMENTS,
    anatomical_to_degrees,
    coordinates_to_clinical,
    moments_to_clinical,
    moments_to_plug_in_gait,
)
from gaitcli.kinematics.model import BODIES, COORDINATES, JOINTS, MOMENTS, RESIDUALS
from gaitcli.signal.cycles import CYCLE_PCT, CYCLE_POINTS, Stride, normalise


def coordinate_columns(result: IdynResult) -> dict:
    """The 27 coordinates (3.1): m and degrees, clinical signs, zero in the standing posture."""
    table = coordinates_to_clinical(result.q)
    return {"time_s": result.time_s, **{name: table[:, k] for k, name in enumerate(COORDINATES)}}


def displayed_angles(result: IdynResult) -> tuple[np.ndarray, tuple[str, ...], str]:
    """The joint angles the tables and plots for people show (deg), their column names and convention:
    the anatomical angles, or the 27 coordinates with ``angles: posture``."""
    if result.angles == "posture" or result.anatomical_angles_rad is None:
        return coordinates_to_clinical(result.q), COORDINATES, CONVENTION
    return (anatomical_to_degrees(result.anatomical_angles_rad), ANATOMICAL_ANGLES,
            f"{ANATOMICAL_CONVENTION}; frames: {result.angle_convention}")


def kinematics_columns(result: IdynResult) -> dict:
    """kinematics.csv: :func:`displayed_angles` in degrees."""
    table, names, _ = displayed_angles(result)
    return {"time_s": result.time_s, **{name: table[:, k] for k, name in enumerate(names)}}


def displayed_moments(result: IdynResult, moments_Nm: np.ndarray | None = None) -> tuple[np.ndarray, tuple, str]:
    """The joint moments (n, 21) N·m the tables and plots for people show, their column names and convention:
    Plug-in Gait's (``moments: plug_in_gait``) or positive in the sense of each angle (``coordinate``).
    ``moments_Nm`` (n, 7, 3) replaces the result's own (the known ones, say)."""
    if result.moment_convention == "plug_in_gait":
        vectors = result.joint_moments_anatomical_Nm if moments_Nm is None else moments_Nm
        return moments_to_plug_in_gait(vectors), PIG_MOMENTS, PIG_CONVENTION
    vectors = result.joint_moments_Nm if moments_Nm is None else moments_Nm
    return moments_to_clinical(vectors), MOMENTS, f"{CONVENTION}; components in {result.frames} frames"


def known_shown_moments_Nm(result: IdynResult) -> np.ndarray:
    """:func:`displayed_moments` (n, 21) with NaN where the load they depend on is unknown."""
    source = (result.joint_moments_anatomical_Nm if result.moment_convention == "plug_in_gait"
              else result.joint_moments_Nm)
    return displayed_moments(result, np.where(result.moment_known[..., None], source, np.nan))[0]


def moment_columns(result: IdynResult) -> dict:
    """21 moments in N·m (``<name>_moment``) then in N·m/kg (``<name>_moment_per_kg``), NaN where the foot load
    they depend on is unknown; names and signs by :func:`displayed_moments`."""
    table = known_shown_moments_Nm(result)
    names = displayed_moments(result)[1]
    columns = {"time_s": result.time_s}
    columns.update({name: table[:, k] for k, name in enumerate(names)})
    columns.update({f"{name}_per_kg": table[:, k] / result.mass_kg for k, name in enumerate(names)})
    columns["right_foot_load_known"] = result.foot_measured["r"].astype(int)
    columns["left_foot_load_known"] = result.foot_measured["l"].astype(int)
    return columns


def power_columns(result: IdynResult) -> dict:
    """Total and sagittal joint powers of hips, knees and ankles in W and W/kg, NaN where the moment is unknown
    (positive: generated)."""
    columns = {"time_s": result.time_s}
    for k, joint in enumerate(JOINTS):
        if joint == "lumbar":
            continue
        known = result.moment_known[:, k]
        for label, values in (("power", result.joint_powers_W), ("sagittal_power", result.joint_powers_sagittal_W)):
            shown = np.where(known, values[:, k], np.nan)
            columns[f"{joint}_{label}_W"] = shown
            columns[f"{joint}_{label}_W_per_kg"] = shown / result.mass_kg
    return columns


def residual_columns(result: IdynResult) -> dict:
    """The 6 pelvis residuals (3.22), NaN where a foot on the ground is off the plates."""
    values = np.column_stack([result.residual_force_N, result.residual_moment_Nm])
    values[~result.measured] = np.nan
    units = ["N"] * 3 + ["Nm"] * 3
    columns = {"time_s": result.time_s}
    columns.update({f"{name}_{u}": values[:, k] for k, (name, u) in enumerate(zip(RESIDUALS, units))})
    columns["all_contacts_measured"] = result.measured.astype(int)
    return columns


def grf_columns(result: IdynResult) -> dict[str, np.ndarray]:
    """Each foot's ground reaction in % of body weight: ``grf_<side>_vertical``, ``_anterior`` (along the walk) and
    ``_medial`` (towards the other foot: +y for the right, −y for the left) ``_pct_body_weight``; NaN where the
    foot's load is not known (on the ground off the plates)."""
    weight_N = result.mass_kg * GRAVITY_M_S2
    out = {}
    for side in ("r", "l"):
        load = result.trial.feet.get(side)
        force = np.full((result.trial.n_frames, 3), np.nan) if load is None or not load.on_plates else \
            np.where(result.foot_measured[side][:, None], load.force_N, np.nan)
        medial = 1.0 if side == "r" else -1.0
        for name, component in (("vertical", force[:, 2]), ("anterior", force[:, 0]), ("medial", medial * force[:, 1])):
            out[f"grf_{side}_{name}_pct_body_weight"] = 100.0 * component / weight_N
    return out


def cycle_columns(result: IdynResult) -> dict:
    """Every complete stride of each side normalised to 0–100 % (long format: one block per stride): the angles,
    moments (N·m/kg) and total joint powers (W/kg) of the tables and each foot's ground reaction in % of body
    weight (:func:`grf_columns`); a left stride's pelvis obliquity and rotation negated (:data:`MIRRORED_ON_LEFT`,
    as Plug-in Gait reports the left side)."""
    kin, angle_names, _ = displayed_angles(result)
    mom = known_shown_moments_Nm(result) / result.mass_kg
    powers = {name: values for name, values in power_columns(result).items()
              if name.endswith("_power_W_per_kg") and "sagittal" not in name}
    grf = grf_columns(result)
    values = np.column_stack([kin, mom, *powers.values(), *grf.values()])
    names = list(angle_names) + [f"{m}_per_kg" for m in displayed_moments(result)[1]] + list(powers) + list(grf)
    left_sign = np.array([-1.0 if name in MIRRORED_ON_LEFT else 1.0 for name in names])
    blocks = {"cycle_pct": [], "side": [], "stride": [], "start_s": []}
    rows = []
    for k, stride in enumerate(result.strides):
        rows.append(normalise(values, result.time_s, stride) * (left_sign if stride.side == "l" else 1.0))
        blocks["cycle_pct"].append(CYCLE_PCT)
        blocks["side"].append(np.full(CYCLE_POINTS, stride.side))
        blocks["stride"].append(np.full(CYCLE_POINTS, k + 1))
        blocks["start_s"].append(np.full(CYCLE_POINTS, stride.start_s))
    columns = {key: (np.concatenate(v) if v else np.zeros(0)) for key, v in blocks.items()}
    table = np.concatenate(rows) if rows else np.zeros((0, len(names)))
    columns.update({name: table[:, k] for k, name in enumerate(names)})
    return columns


#: gait_cycle.csv's columns that say which stride a row is of, before its values
CYCLE_KEYS = {"cycle_pct": "%", "side": "1", "stride": "1", "start_s": "s"}


def cycle_datasets(cycles: dict) -> dict[str, Dataset]:
    """gait_cycle.csv's table (:func:`cycle_columns`) for ``idyn.h5``'s ``gait_cycle/``: the stride keys
    (:data:`CYCLE_KEYS`) one dataset each, the values one (rows, columns) dataset whose ``columns`` attribute
    names them (read back by :func:`gaitcli.io.stage_files.read_idyn_tables`)."""
    names = [name for name in cycles if name not in CYCLE_KEYS]
    rows = len(cycles["cycle_pct"])
    values = np.column_stack([cycles[n] for n in names]) if rows else np.zeros((0, len(names)))
    data = {f"gait_cycle/{key}": Dataset(np.asarray(cycles[key]), unit) for key, unit in CYCLE_KEYS.items()}
    data["gait_cycle/values"] = Dataset(values, "deg, N*m/kg, W/kg, % body weight", {
        "columns": ",".join(names), "convention": "gait_cycle.csv's: the tables' angles (deg), moments (N*m/kg) and "
                                                  "total powers (W/kg), ground reactions in % of body weight"})
    return data


def rms(values: np.ndarray) -> float:
    """Root mean square of the vector magnitudes over the finite rows (NaN when none)."""
    finite = np.all(np.isfinite(values), axis=1)
    return float(np.sqrt(np.mean(np.sum(values[finite] ** 2, axis=1)))) if finite.any() else float("nan")


def _rms_mm(values: np.ndarray) -> float | None:
    finite = np.isfinite(values)
    return float(1000.0 * np.sqrt(np.mean(values[finite] ** 2))) if finite.any() else None


def summary(result: IdynResult) -> dict:
    """The idyn stage's ``summary.json`` keys: Table 3.1's features, the residuals, the fit quality and
    provenance notes."""
    m = result.measured
    info = {
        "frames": int(result.q.shape[0]),
        "dof": int(result.q.shape[1]),
        "rms_residual_force_N": rms(result.residual_force_N[m]),
        "rms_residual_moment_Nm": rms(result.residual_moment_Nm[m]),
        "residual_frames": int(np.sum(m & np.all(np.isfinite(result.residual_force_N), axis=1))),
        "rms_residual_force_all_frames_N": rms(result.residual_force_N),
        **{k: v for k, v in result.features.as_dict().items()},
        "angles": result.angles,
        "angle_frames": result.angle_convention,
        "moment_convention": result.moment_convention,
        "mass_kg": result.mass_kg,
        "mass_source": result.mass_source,
        "moment_frames": result.frames,
        # the frames at each end of a tracked run whose moments are left unknown (the filter's start-up)
        "filter_edge_frames": int(result.trial.filter_edge_frames),
        "segment_rms_marker_error_mm": {b: float(np.nanmean(result.segment_rms_m[:, i]) * 1000)
                                        if np.isfinite(result.segment_rms_m[:, i]).any() else None
                                        for i, b in enumerate(BODIES)},
        "joint_centre_gap_mm": {j: _rms_mm(result.joint_centre_gap_m[:, k]) for k, j in enumerate(JOINTS)},
        "marker_rms_error_mm": {label: 1000.0 * v for label, v in result.marker_rms_m.items()},
        "locked_segments": list(result.calibration.locked),
        "hat_tracked": result.hat_tracked,
        "notes": result.notes + ([] if result.hat_tracked else [
            "the HAT has no markers of its own: it is locked to the pelvis, so the lumbar moment and the pelvis "
            "residuals are those of a trunk that moves with the pelvis"]),
    }
    posture = result.reference_posture
    if posture is not None:
        info.update({"mass_estimate_kg": posture.mass_estimate_kg, "marker_set": posture.marker_set,
                     "hip_joint_centre": posture.hip_joint_centre, "segment_inertias": posture.segment_inertias,
                     "static": posture.static,
                     "static_frames": None if posture.static_frames is None else list(posture.static_frames)})
        if posture.hip_score_residual_mm:
            info["hip_score_residual_mm"] = dict(posture.hip_score_residual_mm)
    return info


def write_idyn_outputs(folder: Path, result: IdynResult, attrs: dict) -> dict:
    """Write every table of the idyn stage and ``idyn.h5`` into ``folder``; return the summary.

    ``idyn.h5``: ``sagittal/`` the :class:`~gaitcli.dynamics.sagittal.SagittalExport`
    the muscle stage reads back; coordinates and moments in model and clinical signs;
    residuals, segment parameters, joint centres, strides.
    """
    folder = Path(folder)
    write_table(folder / "kinematics.csv", kinematics_columns(result))
    write_table(folder / "coordinates.csv", coordinate_columns(result))
    write_table(folder / "joint_moments.csv", moment_columns(result))
    write_table(folder / "joint_powers.csv", power_columns(result))
    write_table(folder / "residuals.csv", residual_columns(result))
    write_table(folder / "sagittal.csv", sagittal_columns(result.sagittal))
    cycles = cycle_columns(result)
    write_table(folder / "gait_cycle.csv", cycles)
    p = result.parameters
    angles, angle_names, angle_convention = displayed_angles(result)
    shown_moments, shown_names, shown_convention = displayed_moments(result)
    data = record_datasets("sagittal", result.sagittal)
    data.update(record_datasets("strides", list(result.strides)))
    data.update(cycle_datasets(cycles))
    data.update({
        "time": Dataset(result.time_s, "s"),
        "coordinates": Dataset(result.q, "m, rad", {"columns": ",".join(COORDINATES),
                                                     "convention": "model (3.1): Cardan x-y-z pelvis, y-x-z joints"}),
        "coordinates_clinical": Dataset(coordinates_to_clinical(result.q), "m, deg",
                                        {"columns": ",".join(COORDINATES), "convention": CONVENTION}),
        "angles": Dataset(angles, "deg", {"columns": ",".join(angle_names), "convention": angle_convention}),
        "velocities": Dataset(result.qd, "m/s, rad/s"),
        "accelerations": Dataset(result.qdd, "m/s^2, rad/s^2"),
        "joint_moments": Dataset(result.joint_moments_Nm, "N*m", {
            "axes": "frames, joints (" + ",".join(JOINTS) + "), xyz", "frames": result.frames,
            "convention": "model: moment of the proximal on the distal segment, components in the distal "
                          f"segment's {result.frames} frame"}),
        "joint_moments_clinical": Dataset(moments_to_clinical(result.joint_moments_Nm), "N*m",
                                          {"columns": ",".join(MOMENTS), "convention": CONVENTION}),
        "joint_moments_shown": Dataset(shown_moments, "N*m", {"columns": ",".join(shown_names),
                                                               "convention": shown_convention}),
        "joint_moments_anatomical": Dataset(result.joint_moments_anatomical_Nm, "N*m", {
            "axes": "frames, joints (" + ",".join(JOINTS) + "), xyz",
            "convention": "moment of the proximal on the distal segment, components in the distal segment's "
                          f"anatomical frame ({result.angle_convention})"}),
        "joint_powers": Dataset(result.joint_powers_W, "W", {"joints": ",".join(JOINTS),
                                                              "meaning": "M · (ω_child − ω_parent), generated +"}),
        "joint_powers_sagittal": Dataset(result.joint_powers_sagittal_W, "W", {
            "joints": ",".join(JOINTS), "meaning": "about the distal segment's anatomical medio-lateral axis"}),
        "joint_moments_global": Dataset(result.joint_moments_global_Nm, "N*m", {"frames": "global (model axes)"}),
        "joint_moments_known": Dataset(result.moment_known.astype(np.int8), "1", {
            "joints": ",".join(JOINTS), "meaning": "1 where the foot load the joint's moment depends on is known "
                                                   "(the CSVs and plots are NaN elsewhere)"}),
        "residuals/force": Dataset(result.residual_force_N, "N", {"frames": "global"}),
        "residuals/moment": Dataset(result.residual_moment_Nm, "N*m", {"frames": "global, about the pelvis CoM"}),
        "residuals/all_contacts_measured": Dataset(result.measured.astype(np.int8), "1"),
        "segments/names": Dataset(np.array(BODIES), "1"),
        "segments/mass": Dataset(p.mass_kg, "kg", {"total_kg": p.total_mass_kg, "body_mass_kg": result.mass_kg}),
        "segments/inertia": Dataset(p.inertia_kgm2, "kg*m^2", {"about": "segment CoM, segment axes"}),
        "segments/joint_in_parent": Dataset(p.joint_in_parent_m, "m"),
        "segments/joint_in_child": Dataset(p.joint_in_child_m, "m"),
        "segments/rms_marker_error": Dataset(result.segment_rms_m, "m"),
        "segments/reference_to_anatomical": Dataset(result.calibration.reference_to_anatomical, "1"),
        "segments/disturbances": Dataset(np.array([str(n) for n in p.notes] or [""]), "1"),
        "joint_centres": Dataset(result.joint_centres_m, "m", {"joints": ",".join(JOINTS)}),
        "joint_centre_gap": Dataset(result.joint_centre_gap_m, "m", {
            "joints": ",".join(JOINTS),
            "meaning": "model joint centre to where the child segment's own markers put it"}),
    })
    write_h5(folder / "idyn.h5", data, attrs)
    return summary(result)


@dataclass(frozen=True)
class IdynOutput:
    """What an ``idyn.h5`` gives the figures and the prediction's reference: the muscle stage's hand-off
    (:class:`~gaitcli.dynamics.sagittal.SagittalExport`: each leg's motion and load, the events, the body
    mass), every complete stride of both sides, and the tables for people
    (:class:`~gaitcli.io.stage_files.IdynTables`)."""

    sagittal: SagittalExport
    strides: list[Stride]
    tables: IdynTables


def read_idyn_output(path: str | Path) -> IdynOutput:
    """The :class:`IdynOutput` of an ``idyn.h5`` (a damaged or foreign file: InputError)."""
    return IdynOutput(read_result(path, SagittalExport, "sagittal", what="gait idyn"),
                      read_result(path, list[Stride], "strides", what="gait idyn"), read_idyn_tables(path))
