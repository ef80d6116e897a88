"""Writes the muscle stage's files: forces.csv, activations.csv, excitations.csv, metabolics.csv,
muscles.h5, summary.json and plots/ (Figs. 4.7–4.9 and the metabolic cost per muscle)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.io.outputs import Dataset, write_h5, write_json, write_table
from gaitcli.muscles.stage import MuscleResult
from gaitcli.report import plots


def per_muscle(result: MuscleResult, values: np.ndarray, suffix: str) -> dict:
    columns = {"time_s": result.time_s}
    columns.update({f"{name}_{suffix}": values[:, k] for k, name in enumerate(result.muscle_names)})
    return columns


def summary(result: MuscleResult, *, phase: str, interval: tuple, elapsed_s: float) -> dict:
    """DESIGN.md's muscle keys plus the solver report and the analysed interval."""
    info = result.summary()
    info.update({
        "side": result.side, "phase": phase, "interval_s": [float(interval[0]), float(interval[1])],
        "periodic": bool(result.periodic), "objective": result.objective, "status": result.status,
        "iterations": int(result.iterations), "speed_m_s": float(result.speed_m_s),
        "ralston_J_per_m": float(result.ralston_J_per_m),
        "metabolic_cost_per_muscle_J": {name: float(v) if np.isfinite(v) else None
                                        for name, v in zip(result.muscle_names, result.metabolic_energy_J)},
        "infeasible_frames": [int(i) for i in result.infeasible_frames],
        "max_infeasibility": float(max(result.infeasibility)) if result.infeasibility else 0.0,
        "notes": list(result.notes), "elapsed_s": round(elapsed_s, 3),
    })
    return info


def write_muscle_outputs(folder: Path, result: MuscleResult, attrs: dict, *, phase: str, interval: tuple,
                         events, elapsed_s: float) -> dict:
    """Write every file of one method's muscle outputs into ``folder``; return the summary."""
    folder = Path(folder)
    write_table(folder / "forces.csv", per_muscle(result, result.forces_N, "force_N"))
    write_table(folder / "activations.csv", per_muscle(result, result.activations, "activation"))
    write_table(folder / "excitations.csv", per_muscle(result, result.excitations, "excitation"))
    metabolics = per_muscle(result, result.metabolic_rate_W, "metabolic_rate_W")
    metabolics["total_metabolic_rate_W"] = result.metabolic_rate_W.sum(axis=1)
    write_table(folder / "metabolics.csv", metabolics)
    joints = "hip flexion, knee flexion, ankle dorsiflexion"
    data = {
        "time": Dataset(result.time_s, "s"),
        "muscles": Dataset(np.array(result.muscle_names), "1"),
        "forces": Dataset(result.forces_N, "N"),
        "activations": Dataset(result.activations, "1"),
        "excitations": Dataset(result.excitations, "1"),
        "fibre_length": Dataset(result.fibre_length_m, "m"),
        "fibre_velocity": Dataset(result.fibre_velocity_m_s, "m/s"),
        "metabolic_rate": Dataset(result.metabolic_rate_W, "W"),
        "joint_moments": Dataset(result.joint_moments_Nm, "N*m", {"columns": joints, "source": "inverse dynamics"}),
        "muscle_moments": Dataset(result.muscle_moments_Nm, "N*m", {"columns": joints}),
        "passive_moments": Dataset(result.passive_moments_Nm, "N*m", {"columns": joints}),
        "damping_moments": Dataset(result.damping_moments_Nm, "N*m", {"columns": joints}),
        "moment_error": Dataset(result.moment_error_Nm, "N*m", {"columns": joints}),
    }
    if result.validation is not None:
        v = result.validation
        data["validation/time"] = Dataset(v.time_s, "s")
        data["validation/angles"] = Dataset(v.angles_rad, "rad", {"columns": "thigh, knee flexion, ankle dorsiflexion"})
        data["validation/rms"] = Dataset(v.rms_deg, "deg")
    if result.moment_shortfall_Nm is not None:
        data["moment_shortfall"] = Dataset(result.moment_shortfall_Nm, "N*m", {
            "columns": joints, "meaning": "required minus achievable moment (EID with relaxed moment equations)"})
    root = dict(attrs)
    root.update({"method": result.method, "objective": result.objective, "converged": bool(result.converged),
                 "solver_status": result.status})
    write_h5(folder / "muscles.h5", data, root)
    info = summary(result, phase=phase, interval=interval, elapsed_s=elapsed_s)
    trial = attrs.get("trial")
    plots.muscle_figures(folder / "plots", result, events, title=f"— {Path(trial).resolve().name}" if trial else "")
    write_json(folder / "summary.json", info)
    return info
