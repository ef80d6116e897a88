"""Writes the muscle stage's files: forces.csv, activations.csv, excitations.csv, metabolics.csv, where the trial
has EMG emg_agreement.csv, and muscles.h5 (the whole :class:`~gaitcli.muscles.stage.MuscleResult` under
``result/``), and gives its summary."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.io.h5 import record_datasets, write_h5
from gaitcli.io.outputs import write_table
from gaitcli.muscles.stage import MuscleResult


def per_muscle(result: MuscleResult, values: np.ndarray, suffix: str) -> dict:
    columns = {"time_s": result.time_s}
    columns.update({f"{name}_{suffix}": values[:, k] for k, name in enumerate(result.muscle_names)})
    return columns


def summary(result: MuscleResult) -> dict:
    """The muscle stage's ``summary.json`` keys: the metabolic cost, the solver's report and the analysed interval."""
    info = result.summary()
    info.update({
        "side": result.side, "phase": result.phase, "interval_s": list(result.interval_s),
        "periodic": bool(result.periodic), "objective": result.objective, "status": result.status,
        "iterations": int(result.iterations), "speed_m_s": float(result.speed_m_s),
        "ralston_J_per_m": float(result.ralston_J_per_m),
        "metabolic_cost_per_muscle_J": {name: float(v) if np.isfinite(v) else None
                                        for name, v in zip(result.muscle_names, result.metabolic_energy_J)},
        "infeasible_frames": [int(i) for i in result.infeasible_frames],
        "max_infeasibility": float(max(result.infeasibility)) if result.infeasibility else 0.0,
        "notes": list(result.notes),
    })
    return info


def muscle_tables(result: MuscleResult) -> dict[str, dict]:
    """The per-muscle tables by file name (``forces``, ``activations``, ``excitations``, ``metabolics`` with the
    total), each its columns by name, units in the names (what the CSVs hold)."""
    metabolics = per_muscle(result, result.metabolic_rate_W, "metabolic_rate_W")
    metabolics["total_metabolic_rate_W"] = result.metabolic_rate_W.sum(axis=1)
    return {"forces": per_muscle(result, result.forces_N, "force_N"),
            "activations": per_muscle(result, result.activations, "activation"),
            "excitations": per_muscle(result, result.excitations, "excitation"), "metabolics": metabolics}


#: the limb's generalized coordinates, the columns of every moment array
JOINT_COLUMNS = "hip flexion, knee flexion, ankle dorsiflexion"


def write_muscle_outputs(folder: Path, result: MuscleResult, attrs: dict) -> dict:
    """Write every table of one method's muscle outputs and ``muscles.h5`` into ``folder``; return the summary."""
    folder = Path(folder)
    for name, columns in muscle_tables(result).items():
        write_table(folder / f"{name}.csv", columns)
    if result.emg is not None:
        agreement = result.emg
        write_table(folder / "emg_agreement.csv", {
            "muscle": agreement.muscles, "channel": agreement.channels, "correlation": agreement.correlation,
            "lag_s": agreement.lag_s, "lagged_correlation": agreement.lagged_correlation,
            "on_off_agreement_pct": agreement.on_off_agreement_pct})
    data = record_datasets("result", result)
    for name in ("joint_moments_Nm", "passive_moments_Nm", "damping_moments_Nm", "muscle_moments_Nm",
                 "moment_error_Nm", "moment_shortfall_Nm"):
        if f"result/{name}" in data:
            data[f"result/{name}"].attrs["columns"] = JOINT_COLUMNS
    data["result/joint_moments_Nm"].attrs["source"] = "inverse dynamics"
    root = dict(attrs)
    root.update({"method": result.method, "objective": result.objective, "converged": bool(result.converged),
                 "solver_status": result.status})
    write_h5(folder / "muscles.h5", data, root)
    return summary(result)
