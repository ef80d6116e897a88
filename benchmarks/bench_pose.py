"""Which pose fit recovers the truth better: ``segment_svd`` (the dissertation's, chained from the pelvis) or
``chain_lsq`` (the whole chain fitted to all markers), on synthetic walks with noise and skin artefact.

For each seed (``gait synth``'s default subject and marker set, 2 mm noise, 10 mm artefact) and hip-centre
error (none, or the static trial's hip centres 25 mm anterior, superior or lateral of the truth), prints per
pose the knee and ankle centres' RMS distance from the truth over stance (mm) and the sagittal hip, knee and
ankle moments' RMS error against the truth where the foot's load is known (N·m/kg), both legs pooled, and the
idyn stage's wall time. With ``--marker-sets``, the same comparison on ``gait synth --marker-set`` trials of
each clinical preset (no hip error; the subject's ``marker_set`` and no map), moments per leg: on Plug-in Gait
``chain_lsq`` raises the hip moment's error (its thigh has only a wand and the knee marker), which is why
``segment_svd`` stays the default. Run: ``python benchmarks/bench_pose.py [--marker-sets]``.
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np

from gaitcli.core.recording import Recording
from gaitcli.dynamics.stage import POSES, IdynConfig, inverse_dynamics_stage, run_idyn
from gaitcli.kinematics.calibration import calibrate
from gaitcli.kinematics.conventions import moments_to_clinical
from gaitcli.kinematics.forward import forward_kinematics
from gaitcli.kinematics.markerset import marker_set, with_fixed_points
from gaitcli.kinematics.model import JOINTS, MOMENTS
from gaitcli.kinematics.subject import Subject
from gaitcli.signal.stage import FilterConfig, filter_trial
from gaitcli.synth import simulate_trial

MASS_KG, STATURE_M = 75.0, 1.78
#: the hip centres' displacement (m: forward, outward, up)
SHIFTS = {"none": None, "25 mm anterior": (0.025, 0, 0), "25 mm superior": (0, 0, 0.025),
          "25 mm lateral": (0, 0.025, 0)}


def errors(trial, result):
    """(joint-centre RMS mm: knee, ankle; sagittal moment RMS N·m/kg: hip, knee, ankle), both legs pooled."""
    truth = forward_kinematics(trial.q, trial.calibration.body).joint_centre_m
    want = moments_to_clinical(trial.joint_moments_Nm) / MASS_KG
    got = moments_to_clinical(result.joint_moments_Nm) / MASS_KG
    centres, moments = {"knee": [], "ankle": []}, {"hip": [], "knee": [], "ankle": []}
    for side in "rl":
        stance = trial.feet[side]["force_N"][:, 2] > 0
        distance = np.linalg.norm(result.joint_centres_m - truth, axis=-1)[stance]
        for joint in centres:
            centres[joint].append(distance[:, JOINTS.index(f"{joint}_{side}")])
        known = result.foot_measured[side]
        for joint in moments:
            k = MOMENTS.index(f"{joint}_{side}_flexion_moment")
            moments[joint].append(got[known, k] - want[known, k])
    rms = lambda parts: float(np.sqrt(np.nanmean(np.concatenate(parts) ** 2)))  # noqa: E731
    return {j: 1000 * rms(v) for j, v in centres.items()}, {j: rms(v) for j, v in moments.items()}


def per_leg_moments(trial, result) -> dict[str, float]:
    """Sagittal moment RMS error (N·m/kg) per joint and leg where that foot's load is known."""
    want = moments_to_clinical(trial.joint_moments_Nm) / MASS_KG
    got = moments_to_clinical(result.joint_moments_Nm) / MASS_KG
    out = {}
    for side in "rl":
        known = result.foot_measured[side]
        for joint in ("hip", "knee", "ankle"):
            k = MOMENTS.index(f"{joint}_{side}_flexion_moment")
            out[f"{joint}_{side}"] = float(np.sqrt(np.mean((got[known, k] - want[known, k]) ** 2)))
    return out


def compare_presets(seeds) -> None:
    """Both poses on synthetic trials of each clinical preset, with only the preset named (no map)."""
    print(f"{'preset':13} {'seed':5} {'pose':12} " + " ".join(f"{j + '_' + s:>8}" for s in "rl"
                                                          for j in ("hip", "knee", "ankle")))
    for name in ("plug_in_gait", "cleveland", "cast"):
        preset = marker_set(name)
        subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set=name)
        for seed in seeds:
            trial = simulate_trial(seed=seed, marker_set=name)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                filtered = filter_trial(Recording(preset.apply(trial.markers), trial.plates,
                                                  subject_metadata=trial.metadata), FilterConfig()).trial
                static = Recording(preset.apply(trial.static), [], subject_metadata=trial.metadata)
                for pose in POSES:
                    rms = per_leg_moments(trial, run_idyn(filtered, static, subject, IdynConfig(pose=pose)))
                    print(f"{name:13} {seed:<5} {pose:12} " + " ".join(f"{v:8.3f}" for v in rms.values()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", nargs="+", type=int, default=[1, 2])
    parser.add_argument("--marker-sets", action="store_true", help="compare on the clinical presets' trials")
    args = parser.parse_args()
    if args.marker_sets:
        compare_presets(args.seeds)
        return
    print(f"{'seed':5} {'hip error':15} {'pose':12} {'knee mm':>8} {'ankle mm':>8} "
          f"{'M hip':>6} {'M knee':>6} {'M ankle':>7} {'idyn s':>7}")
    for seed in args.seeds:
        trial = simulate_trial(seed=seed, plate_noise_N=0.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            filtered = filter_trial(Recording(trial.markers, trial.plates), FilterConfig()).trial
            bell = calibrate(trial.static, mass_kg=MASS_KG, stature_m=STATURE_M)
        for label, shift in SHIFTS.items():
            if shift is None:
                calibration = bell
            else:
                move = {f"HJC{s}": bell.joint_centres_m[f"HJC{s}"] + np.multiply(shift, (1.0, outward, 1.0))
                        for s, outward in (("r", -1.0), ("l", 1.0))}
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    calibration = calibrate(with_fixed_points(trial.static, move), mass_kg=MASS_KG,
                                            stature_m=STATURE_M, hip_method="from_file")
            for pose in POSES:
                start = time.perf_counter()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    result = inverse_dynamics_stage(filtered, calibration, IdynConfig(pose=pose), mass_kg=MASS_KG,
                                                    mass_source="benchmark")
                wall = time.perf_counter() - start
                centres, moments = errors(trial, result)
                print(f"{seed:<5} {label:15} {pose:12} {centres['knee']:8.1f} {centres['ankle']:8.1f} "
                      f"{moments['hip']:6.3f} {moments['knee']:6.3f} {moments['ankle']:7.3f} {wall:7.1f}")


if __name__ == "__main__":
    main()
