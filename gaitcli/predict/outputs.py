"""Writes the predict stage's files: motion.csv, grf.csv, moments.csv, muscles.csv, prosthesis.csv (prosthetic
runs) and predict.h5 (the whole :class:`~gaitcli.predict.stage.PredictResult` under ``result/``); the summary
is the result's."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.io.h5 import record_datasets, write_h5
from gaitcli.io.outputs import write_table
from gaitcli.predict.stage import JOINTS, PredictResult

ANGLE_COLUMNS = ("hip_r_flexion_deg", "knee_r_flexion_deg", "ankle_r_dorsiflexion_deg",
                 "hip_l_flexion_deg", "knee_l_flexion_deg", "ankle_l_dorsiflexion_deg")


def prediction_tables(result: PredictResult) -> dict[str, dict]:
    """The prediction's tables by file name (``motion``, ``grf``, ``moments``, ``muscles`` and with a prosthesis
    ``prosthesis``), each its columns by name, units in the names (what the CSVs hold)."""
    motion = {"time_s": result.time_s, "cycle_pct": result.cycle_pct,
              "hip_x_m": result.coordinates[:, 0], "hip_z_m": result.coordinates[:, 1],
              "trunk_lean_deg": np.degrees(result.coordinates[:, 2])}  # y3 > 0: the HAT's CoM ahead of the hip
    motion.update({name: result.clinical_angles_deg[:, k] for k, name in enumerate(ANGLE_COLUMNS)})
    pct = 100 * result.point_time_s / result.period_s
    grf = {"time_s": result.point_time_s, "cycle_pct": pct, "phase": result.point_phase}
    for k, name in enumerate(("right_fx_N", "right_fz_N", "left_fx_N", "left_fz_N")):
        grf[name] = result.grf_N[:, k]
        grf[name.replace("_N", "_N_per_kg")] = result.grf_N[:, k] / result.body_mass_kg
    moments = {"time_s": result.point_time_s, "cycle_pct": pct, "phase": result.point_phase}
    for k, joint in enumerate(JOINTS):
        moments[f"{joint}_moment_Nm"] = result.joint_moments_Nm[:, k]
        moments[f"{joint}_muscle_moment_Nm"] = result.muscle_moments_Nm[:, k]
    muscles = {"time_s": result.time_s, "cycle_pct": result.cycle_pct}
    for k, name in enumerate(result.muscle_names):
        muscles[f"{name}_force_N"] = result.muscle_forces_N[:, k]
        muscles[f"{name}_activation"] = result.activations[:, k]
        muscles[f"{name}_excitation"] = result.excitations[:, k]
        muscles[f"{name}_metabolic_rate_W"] = result.metabolic_rate_W[:, k]
    tables = {"motion": motion, "grf": grf, "moments": moments, "muscles": muscles}
    if result.prosthesis is not None:
        tables["prosthesis"] = prosthesis_table(result)
    return tables


def write_predict_outputs(folder: Path, result: PredictResult, attrs: dict) -> dict:
    """Write every table of a prediction (:func:`prediction_tables`) and ``predict.h5`` into ``folder``; return
    the summary."""
    folder = Path(folder)
    for name, columns in prediction_tables(result).items():
        write_table(folder / f"{name}.csv", columns)
    data = record_datasets("result", result)
    root = dict(attrs)
    root.update({"converged": bool(result.converged), "solver_status": result.status,
                 "angle_convention": "coordinates: the model's clockwise-positive angles (Diss. 5.2.2); "
                                     "clinical_angles_deg: hip/knee flexion, ankle dorsiflexion positive"})
    write_h5(folder / "predict.h5", data, root)
    return result.summary()


def prosthesis_table(result: PredictResult) -> dict:
    """The prostheses over the cycle (5.58)–(5.59): per side the ankle angle (the model's y6/y9, rad, and
    clinical dorsiflexion, deg) and the spring, damping and total moments, N·m, plantarflexing positive."""
    curve = result.prosthesis
    table = {"time_s": result.time_s, "cycle_pct": result.cycle_pct}
    for k, (side, index) in enumerate((("r", 5), ("l", 8))):
        y = result.coordinates[:, index]
        spring = curve.spring_moment_Nm(y)
        table[f"ankle_{side}_angle_rad"] = y
        table[f"ankle_{side}_dorsiflexion_deg"] = result.clinical_angles_deg[:, 2 + 3 * k]
        table[f"ankle_{side}_spring_moment_Nm"] = spring
        table[f"ankle_{side}_damping_moment_Nm"] = result.ankle_moment_Nm[:, k] - spring
        table[f"ankle_{side}_moment_Nm"] = result.ankle_moment_Nm[:, k]
    return table
