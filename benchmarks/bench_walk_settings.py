"""Which of the synthetic walk's settings make it crouch: ``make_walk``'s solves, one setting at a time.

Solves the dissertation's prediction for the walk's subject, speed and step (``gaitcli.synth.predicted``: 75 kg,
1.78 m, 1.30 m/s, steps 0.694 m, the reference WALK_REFERENCE) from the default guess with Table A.1's muscles
(the "plain" start), then, from that start, the second solve with each variant of WALK_TRACKING's settings at the
muscles' F_max × ``--scale``. Prints, per solve, IPOPT's status, iterations and seconds, J, Et and the
dissertation's Jdev, heel-off (% of the cycle), and the right leg's angles against Winter's adult curves
(``gaitcli.synth.gait``): the loading-response knee peak (0–25 %; Winter 19°), the stance dorsiflexion peak
(10–60 %; Winter 10°), the ankle at heel strike (Winter 0°) and each joint's RMS difference (bench_synth_walk's
:func:`winter_figures`). The shipped walk (made by ``make_walk``) is printed first for comparison.
``--joint-sd-scale k``: the second solve tracks the reference's knee and ankle angles with their SDs × k (k < 1:
a stiffer hold on the kinematics; Jdev is still reported against the reference as it is); ``--grf-sd-scale k``
its ground reactions' (k > 1: a looser hold on the reference's, which come from a 0.88 m/s walk; what k = 3
showed is in benchmarks/README.md, "The synthetic walk").
``--mumps-scaling``: MUMPS with its own row/column scaling (IPOPT's defaults 7 and 77; ``gait predict`` turns it
off, faster on its default problems): without it some of these solves stall in MUMPS's factorization
(benchmarks/README.md, "The synthetic walk").
Run: ``python benchmarks/bench_walk_settings.py [--scale 0.65] [--variants shipped cop hip swing moment trunk]
[--start plain.csv] [--joint-sd-scale 0.5] [--grf-sd-scale 3] [--mumps-scaling]`` (``--start``: a plain start
saved by an earlier run's ``--save-start``; each solve takes 2–10 minutes on one core, some variants longer).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from pathlib import Path

import numpy as np
from bench_synth_walk import winter_figures

# timing first, before numpy: one thread, Agg backend (its import sets the environment)
from timing import one_core

from gaitcli.kinematics.conventions import walker_to_clinical
from gaitcli.predict.guess import initial_guess
from gaitcli.predict.layout import DesignLayout
from gaitcli.predict.model import WalkerParameters, WalkingModel
from gaitcli.predict.problem import Transcriber
from gaitcli.predict.reference import VARIABLES, read_reference
from gaitcli.predict.solve import NlpCache, solve_windowed
from gaitcli.predict.stage import PredictConfig, evaluate_design, settings_of, violated_groups, walker_muscles
from gaitcli.signal.bands import Band
from gaitcli.synth import predicted as walk

#: the second solve's variants: WALK_TRACKING's settings kept (each alone, or all)
VARIANTS = {"shipped": tuple(walk.WALK_TRACKING), "cop": ("cop_sd_m",), "trunk": ("trunk_rate_sd_deg_s",),
            "moment": ("moment_tolerance_Nm",), "hip": ("swing_hip_moment_Nm_per_kg", "hip_moment_Nm_per_kg"),
            "swing": ("swing_hip_moment_Nm_per_kg",)}


def walk_figures(x: np.ndarray) -> dict:
    """The walk χ's heel-off (% of the cycle), ankle angle at heel strike and right-leg :func:`winter_figures`."""
    durations = walk.walk_durations(x)
    phase = np.arange(400) / 400
    y, _, _ = walk.walker_cycle(phase * float(np.sum(durations)), x)
    angles = walker_to_clinical(y)
    return {"heel_off_pct": round(100 * walk.phase_of(durations)[3][1], 1),
            "heel strike ankle deg": round(float(angles[0, 2]), 1), **winter_figures(phase, *angles[:, :3].T)}


def sds_scaled(reference: Band, joint_scale: float, grf_scale: float) -> Band:
    """``reference`` with its knee and ankle angles' SDs × ``joint_scale`` and its ground reactions' × ``grf_scale``
    (both legs)."""
    scale = {name: joint_scale if name.startswith(("knee_", "ankle_")) else grf_scale if name.startswith("grf_")
             else 1.0 for name in VARIABLES}
    return dataclasses.replace(reference, sd={name: sd * scale[name] for name, sd in reference.sd.items()})


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scale", type=float, default=walk.WALK_STRENGTH_SCALE, help="the second solve's F_max")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--start", type=Path, help="a plain start (χ, one value per line) instead of solving it")
    parser.add_argument("--save-start", type=Path, help="write the plain start's χ here")
    parser.add_argument("--joint-sd-scale", type=float, default=1.0,
                        help="the second solve's knee and ankle SDs × this (module docstring)")
    parser.add_argument("--grf-sd-scale", type=float, default=1.0,
                        help="the second solve's ground-reaction SDs × this (module docstring)")
    parser.add_argument("--mumps-scaling", action="store_true",
                        help="MUMPS with its own row/column scaling, IPOPT's defaults (module docstring)")
    args = parser.parse_args()
    options = {"ipopt.mumps_permuting_scaling": 7, "ipopt.mumps_scaling": 77} if args.mumps_scaling else None
    one_core()
    reference = read_reference(walk.WALK_REFERENCE)
    params = WalkerParameters.from_subject(**walk.WALK_SUBJECT)
    step_m = walk.STRIDE_PER_STATURE * walk.WALK_SUBJECT["stature_m"] / 2

    def config(scale):
        return PredictConfig(speed_m_s=walk.WALK_SPEED_M_S, nodes=walk.WALK_NODES, strength_scale=scale)

    def problem(scale):
        cfg = config(scale)
        transcriber = Transcriber(cfg.nodes, model=WalkingModel(params), muscles=walker_muscles(cfg, None))
        return cfg, transcriber, dataclasses.replace(settings_of(cfg), step_m=step_m)

    def show(label, cfg, x, solved=None, seconds=None):
        summary = evaluate_design(cfg, x, reference=reference, params=params).summary()
        row = {"solve": label}
        if solved is not None:
            row.update(status=solved.outcome.status, iterations=solved.outcome.iterations, s=round(seconds))
        row.update(J=round(summary["objective"], 2), Et_J_per_m=round(summary["cost_of_transport_J_per_m"], 1),
                   Jdev=round(summary["deviation"], 1), **walk_figures(x))
        # the constraint groups violated at the dissertation's settings (εm 2 N·m; no hip bounds)
        row["violated"] = {k: round(v, 4) for k, v in violated_groups(summary["violations"]).items()}
        print(json.dumps(row, ensure_ascii=False), flush=True)

    show(f"shipped walk (F_max × {walk.WALK_STRENGTH_SCALE:g})", config(walk.WALK_STRENGTH_SCALE), walk.shipped_walk())
    cache = NlpCache()  # this run's built problems and compiled solvers
    cfg, transcriber, plain = problem(1.0)
    if args.start is not None:
        start = np.loadtxt(args.start)
        show(f"plain start from {args.start}", cfg, start)
    else:
        x = initial_guess(transcriber, reference, plain, symmetric=True)
        rows_at, rows, _ = DesignLayout.build(walk.WALK_NODES, symmetric=True).blocks["steps"]
        x[rows_at:rows_at + rows] = step_m
        began = time.perf_counter()
        solved = solve_windowed(transcriber, reference, x, plain, symmetric=True, options=options, cache=cache)
        start = solved.x
        show("plain start (F_max × 1, the dissertation's settings)", cfg, start, solved, time.perf_counter() - began)
    if args.save_start is not None:
        np.savetxt(args.save_start, start, fmt="%.17g")
    cfg, transcriber, plain = problem(args.scale)
    held = sds_scaled(reference, args.joint_sd_scale, args.grf_sd_scale)
    held_by = (f", knee and ankle SD × {args.joint_sd_scale:g}" if args.joint_sd_scale != 1.0 else "") + \
        (f", GRF SD × {args.grf_sd_scale:g}" if args.grf_sd_scale != 1.0 else "")
    for name in args.variants:
        settings = dataclasses.replace(plain, **{k: walk.WALK_TRACKING[k] for k in VARIANTS[name]})
        began = time.perf_counter()
        solved = solve_windowed(transcriber, held, start, settings, symmetric=True, options=options, cache=cache)
        show(f"{name}: {', '.join(VARIANTS[name])} (F_max × {args.scale:g}{held_by})", cfg, solved.x, solved,
             time.perf_counter() - began)


if __name__ == "__main__":
    main()
