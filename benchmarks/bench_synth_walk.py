"""The predicted synthetic walk (``gait synth --gait predicted``) against issue 11's typical-adult targets.

For each seed: writes the default subject's trial (75 kg, 1.78 m, default noise and artefact) and runs SO, MSO
and EID on both legs through the ``gait`` command; prints each method's convergence, its infeasible frames and
their largest excitation bound violation, and the metabolic energy. From the truth: the swing-phase hip
moment's range (the issue asks ±0.3 N·m/kg), the vertical ground reaction's range, and how far the right leg's
sagittal angles are from Winter's adult curves (``gaitcli.synth.gait``: RMS over the cycles from right heel
strike, and the loading-response knee flexion and the stance dorsiflexion peaks beside Winter's 19° and 10°).
With ``--gait normative`` the same for the normative curves.
Run: ``python benchmarks/bench_synth_walk.py [--seeds 1 2] [--gait predicted]``.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.synth.gait import ANKLE_DORSIFLEXION, HIP_FLEXION, KNEE_FLEXION, periodic_curve


def gait(*args, cwd: Path) -> int:
    return subprocess.run([sys.executable, "-m", "gaitcli", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True).returncode


def truth_figures(folder: Path, mass_kg: float) -> dict:
    """From the truth tables: each leg's swing hip moment range (N·m/kg) and the vertical GRF's range (BW)."""
    moments = pd.read_csv(folder / "truth" / "joint_moments.csv")
    grf = pd.read_csv(folder / "truth" / "grf.csv")
    out = {}
    for side in "rl":
        swing = grf[f"foot_{side}_force_z_N"].to_numpy() <= 0
        hip = moments[f"hip_{side}_flexion_moment"].to_numpy()[swing] / mass_kg
        out[f"swing hip {side} N·m/kg"] = [round(float(hip.min()), 2), round(float(hip.max()), 2)]
    total = (grf["foot_r_force_z_N"] + grf["foot_l_force_z_N"]).to_numpy() / (mass_kg * 9.81)
    out["Fz BW"] = [round(float(total.min()), 2), round(float(total.max()), 2)]
    return {**out, **sagittal_figures(folder)}


def sagittal_figures(folder: Path) -> dict:
    """The truth's right-leg :func:`winter_figures` over whole cycles from right heel strike."""
    kinematics = pd.read_csv(folder / "truth" / "kinematics.csv")
    events = pd.read_csv(folder / "truth" / "events.csv")
    strikes = events[(events.side == "r") & (events.event == "heel_strike")].time_s.to_numpy()
    t = kinematics.time_s.to_numpy()
    within = (t >= strikes[0]) & (t < strikes[-1])
    k = np.searchsorted(strikes, t[within], side="right") - 1
    phase = (t[within] - strikes[k]) / (strikes[k + 1] - strikes[k])
    return winter_figures(phase, *(kinematics[f"{joint}_r_flexion"].to_numpy()[within]
                                   for joint in ("hip", "knee", "ankle")))


def winter_figures(phase, hip, knee, ankle) -> dict:
    """One leg's hip flexion, knee flexion and ankle dorsiflexion (degrees, clinical signs) at ``phase`` (fractions
    of the cycle from heel strike) against Winter's curves: each one's RMS difference, the knee's peak in 0–25 %
    and the ankle's in 10–60 % of the cycle."""
    out = {}
    for joint, angle, curve in (("hip", hip, HIP_FLEXION), ("knee", knee, KNEE_FLEXION),
                                ("ankle", ankle, ANKLE_DORSIFLEXION)):
        rms = np.sqrt(np.mean((angle - periodic_curve(curve, phase)) ** 2))
        out[f"{joint}_r_flexion RMS vs Winter deg"] = round(float(rms), 1)
    out["loading knee flexion deg"] = round(float(knee[phase < 0.25].max()), 1)
    out["stance dorsiflexion deg"] = round(float(ankle[(phase > 0.1) & (phase < 0.6)].max()), 1)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    parser.add_argument("--gait", default="predicted", choices=("predicted", "normative"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for seed in args.seeds:
            trial = root / f"seed{seed}"
            if gait("synth", trial, "--seed", seed, "--gait", args.gait, cwd=root) != 0:
                raise SystemExit(f"gait synth failed for seed {seed}")
            print(f"seed {seed}, --gait {args.gait}:", json.dumps(truth_figures(trial, 75.0), ensure_ascii=False))
            for method in ("so", "mso", "eid"):
                for side in "rl":
                    out = root / f"out_{seed}_{method}_{side}"
                    code = gait("muscles", trial, "--method", method, "--side", side, "--no-plots", "-o", out,
                                cwd=root)
                    info = json.loads((out / "muscles" / method / "summary.json").read_text())
                    frames = info.get("infeasible_frames") or []
                    worst = info.get("max_infeasibility") or 0.0
                    energy = info.get("metabolic_cost_J")
                    print(f"  {method:4} {side}: exit {code}, converged {info['converged']}, infeasible frames "
                          f"{len(frames)} (by ≤ {worst:.3f}), metabolic "
                          f"{'-' if energy is None else f'{energy:.0f} J'}")


if __name__ == "__main__":
    main()
