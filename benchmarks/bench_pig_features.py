"""Sagittal joint moments of Plug-in Gait sessions with a real lab's extra features, against the truth and
against Vicon (hip and knee moments were 0.37–0.77 of Vicon's in two real sessions the project does not hold).

Run from the repository root: ``python benchmarks/bench_pig_features.py [--shared PATH]``. Prints; asserts
nothing.

1. Synthetic (``simulate_trial(marker_set="plug_in_gait")``: 1 mm noise, 10 mm skin artefact, the real filter at its
   defaults, a Plug-in Gait session's 8 Hz markers and Nexus's plates (unfiltered, each frame the mean of its
   samples), unless a row says; seeds 0, 1, 2): the static as it is; with a knee alignment device instead of the knee
   markers (``synth/devices.py``); with medial knee and ankle markers riding thigh and shank with their own noise and
   artefact (``medial_markers=True``), the same mirrored from the lateral ones through the true joint centres (their
   noise the lateral's reversed: the earlier benchmark's), and with thigh and shank clusters too; over three plates
   (``plates=3``); at 120 Hz (plates 1200 Hz, ``marker_rate_hz=120``); all of these together; other cut-offs
   (markers/plates Hz: the dissertation's 6/6 among them); noise-free, filtered, with only the plates filtered, and
   with nothing filtered (the method's own error; the differences are the filter's and the noise's share). Per side
   and joint: RMS against the truth (N·m/kg, where the moment is known: the foot's load known, outside the filter's
   edge frames) and the slope of the least-squares line of gaitcli's against the truth. The synthetic body's
   segments are de Leva's, and so are the subject's (``segment_inertias: de_leva``, as ``gait synth`` writes it).
2. ``../shared/data/pig`` (Vicon's own moments in the C3D) rewritten with: medial knee and ankle markers
   (the lateral ones mirrored through Vicon's own FEO/TIO), thigh and shank clusters (three markers each, rigid in
   Vicon's femur and tibia frames FEO/FEA/FEL/FEP, TIO/…), a sacral marker in place of the PSIS markers, and a
   knee alignment device in the static; each through ``gait idyn`` (``bench_pig.run_session``; the legs' segments
   Plug-in Gait's, the default of such a session). Per joint: r,
   slope and RMS against Vicon over the frames where both have the foot's load. Vicon processed this session
   without a device (Test.vsk: thigh and shank rotations 0), so the device's row is not like for like: its
   shank rotation offsets (the tibial wand against the device's knee axis) turn the shank's frame, and the knee
   moment's components with it.
"""

from __future__ import annotations

import argparse
import shutil
import tempfile
import warnings
from pathlib import Path

import ezc3d
import numpy as np
from bench_pig import MOMENTS, ROOT, read_csv, run_session, vicon_points

from gaitcli.core.recording import Markers, Recording
from gaitcli.dynamics.stage import IdynConfig, run_idyn
from gaitcli.kinematics.conventions import PIG_MOMENTS, moments_to_clinical, moments_to_plug_in_gait
from gaitcli.kinematics.markerset import marker_set
from gaitcli.kinematics.model import JOINTS
from gaitcli.kinematics.model import MOMENTS as MODEL_MOMENTS
from gaitcli.kinematics.subject import Subject
from gaitcli.signal.stage import FilterConfig, filter_trial
from gaitcli.synth import simulate_trial
from gaitcli.synth.devices import with_knee_alignment_device

MASS_KG, STATURE_M = 75.0, 1.78
SAGITTAL = [(j, s) for s in "rl" for j in ("hip", "knee", "ankle")]
#: point slots of ../shared/data/pig that gaitcli does not read (arms, Vicon's pelvis points): the added markers'
SLOTS = ("LUPA", "LELB", "LFRM", "LWRA", "LWRB", "LFIN", "RUPA", "RELB", "RFRM", "RWRA", "RWRB", "RFIN",
         "PELO", "PELA", "PELL", "PELP", "LFOO", "LFOA", "LFOL", "LFOP", "RFOO", "RFOA", "RFOL", "RFOP")


def fit(got: np.ndarray, want: np.ndarray) -> tuple[float, float, float]:
    """(r, slope of got against want, RMS) over the finite samples."""
    seen = np.isfinite(got) & np.isfinite(want)
    got, want = got[seen], want[seen]
    return (float(np.corrcoef(got, want)[0, 1]), float(np.polyfit(want, got, 1)[0]),
            float(np.sqrt(np.mean((got - want) ** 2))))


def with_medial_markers(markers: Markers, centres: dict[str, np.ndarray]) -> Markers:
    """``markers`` with RKNM/LKNM and RMED/LMED: the knee and ankle markers mirrored through the joint centres."""
    columns = {lab: markers.positions_m[:, i] for i, lab in enumerate(markers.labels)}
    for side, prefix in (("r", "R"), ("l", "L")):
        columns[f"{prefix}KNM"] = 2 * centres[f"KJC{side}"] - columns[f"{prefix}KNE"]
        columns[f"{prefix}MED"] = 2 * centres[f"AJC{side}"] - columns[f"{prefix}ANK"]
    return Markers(tuple(columns), np.stack(list(columns.values()), axis=1), markers.rate_hz, markers.first_frame)


def with_clusters(markers: Markers, centres: dict[str, np.ndarray], rng: np.random.Generator) -> Markers:
    """``markers`` with thigh and shank clusters (RTH1–3, RSH1–3, …): three markers each, rigid in a frame of the
    true joint centres and the knee marker's direction, 1 mm noise. Plug-in Gait tracks by its wands and
    ignores them, as Nexus does: they test that their presence changes nothing."""
    columns = {lab: markers.positions_m[:, i] for i, lab in enumerate(markers.labels)}

    def unit(v):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    for side, prefix in (("r", "R"), ("l", "L")):
        for segment, top, bottom in (("TH", "HJC", "KJC"), ("SH", "KJC", "AJC")):
            proximal = unit(centres[f"{top}{side}"] - centres[f"{bottom}{side}"])
            knee = columns[f"{prefix}KNE"] - centres[f"KJC{side}"]
            lateral = unit(knee - np.sum(knee * proximal, axis=-1, keepdims=True) * proximal)
            anterior = np.cross(proximal, lateral) * (1 if side == "r" else -1)
            first = (centres[f"{top}{side}"] + centres[f"{bottom}{side}"]) / 2 + 0.07 * lateral
            for k, p in enumerate((first, first + 0.05 * anterior, first + 0.06 * proximal)):
                columns[f"{prefix}{segment}{k + 1}"] = p + rng.normal(0.0, 0.001 / np.sqrt(3), p.shape)
    return Markers(tuple(columns), np.stack(list(columns.values()), axis=1), markers.rate_hz, markers.first_frame)


def synthetic(seed: int) -> None:
    """The synthetic variants against the truth, per joint and side over the frames whose moments are known (the
    foot's load known, outside the filter's edge frames: ``IdynResult.moment_known``)."""
    trial = simulate_trial(seed=seed, marker_set="plug_in_gait")
    three = simulate_trial(seed=seed, marker_set="plug_in_gait", plates=3)
    medial = simulate_trial(seed=seed, marker_set="plug_in_gait", medial_markers=True)
    fast = simulate_trial(seed=seed, marker_set="plug_in_gait", marker_rate_hz=120.0)
    every = simulate_trial(seed=seed, marker_set="plug_in_gait", plates=3, medial_markers=True, marker_rate_hz=120.0)
    exact = simulate_trial(seed=seed, marker_set="plug_in_gait", noise_mm=0.0, artefact_mm=0.0)
    preset = marker_set("plug_in_gait")
    subject = Subject(mass_kg=MASS_KG, stature_m=STATURE_M, sex="male", marker_set="plug_in_gait",
                      hip_joint_centre="davis", segment_inertias="de_leva")  # the synthetic body's, as gait synth's
    walk_centres = trial.joint_centres_m()
    static_centres = trial.calibration.joint_centres_m
    mirrored = with_medial_markers(trial.markers, walk_centres)
    mirrored_static = with_medial_markers(trial.static, static_centres)
    rng = np.random.default_rng(7)

    def device(source):
        return with_knee_alignment_device(source.static, source.calibration.joint_centres_m)

    variants = {
        "as recorded": (trial, trial.markers, trial.static, FilterConfig()),
        "knee alignment device": (trial, trial.markers, device(trial), FilterConfig()),
        "medial markers": (medial, medial.markers, medial.static, FilterConfig()),
        "medial markers, mirrored": (trial, mirrored, mirrored_static, FilterConfig()),
        "medial markers + clusters": (medial, with_clusters(medial.markers, medial.joint_centres_m(), rng),
                                      with_clusters(medial.static, static_centres, rng), FilterConfig()),
        "three plates": (three, three.markers, three.static, FilterConfig()),
        "120 Hz (plates 1200 Hz)": (fast, fast.markers, fast.static, FilterConfig()),
        "all: KAD+med+cl+3pl+120Hz": (every, with_clusters(every.markers, every.joint_centres_m(), rng),
                                      with_knee_alignment_device(with_clusters(every.static, static_centres, rng),
                                                                 static_centres), FilterConfig()),
        "6/6 Hz (the dissertation's)": (trial, trial.markers, trial.static, FilterConfig(cutoff_hz=6.0,
                                                                                         force_cutoff_hz=6.0)),
        "6/0 Hz (plates unfiltered)": (trial, trial.markers, trial.static, FilterConfig(cutoff_hz=6.0,
                                                                                        force_cutoff_hz=0.0)),
        "8/8 Hz": (trial, trial.markers, trial.static, FilterConfig(cutoff_hz=8.0, force_cutoff_hz=8.0)),
        "8/20 Hz": (trial, trial.markers, trial.static, FilterConfig(force_cutoff_hz=20.0)),
        "8/0 Hz, plates sampled": (trial, trial.markers, trial.static, FilterConfig(plate_frames="sample")),
        "10/30 Hz": (trial, trial.markers, trial.static, FilterConfig(cutoff_hz=10.0, force_cutoff_hz=30.0)),
        "all, 6/6 Hz": (every, with_clusters(every.markers, every.joint_centres_m(), rng),
                        with_knee_alignment_device(with_clusters(every.static, static_centres, rng), static_centres),
                        FilterConfig(cutoff_hz=6.0, force_cutoff_hz=6.0)),
        "noise-free, filtered": (exact, exact.markers, exact.static, FilterConfig()),
        "noise-free, 6/6 Hz": (exact, exact.markers, exact.static, FilterConfig(cutoff_hz=6.0, force_cutoff_hz=6.0)),
        "noise-free, 0 Hz markers": (exact, exact.markers, exact.static, FilterConfig(cutoff_hz=0.0)),
        "noise-free, not filtered": (exact, exact.markers, exact.static,
                                     FilterConfig(cutoff_hz=0.0, force_cutoff_hz=0.0)),
    }
    print(f"Synthetic Plug-in Gait walk, seed {seed}: sagittal moments against the truth (RMS N·m/kg, slope); "
          "filter auto (8 Hz markers, Nexus's plates) unless said")
    print(f"{'variant':28s} " + " ".join(f"{j + '_' + s:>15s}" for j, s in SAGITTAL))
    for name, (source, walk, static, cfg) in variants.items():
        truth = moments_to_clinical(source.joint_moments_Nm) / MASS_KG
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            filtered = filter_trial(Recording(preset.apply(walk), source.plates, subject_metadata=source.metadata),
                                    cfg, marker_set="plug_in_gait").trial
            result = run_idyn(filtered, Recording(preset.apply(static), [], subject_metadata=source.metadata),
                              subject, IdynConfig())
        shown = moments_to_plug_in_gait(result.joint_moments_anatomical_Nm) / MASS_KG
        cells = []
        for joint, side in SAGITTAL:
            sense = "plantarflexor" if joint == "ankle" else "extensor"
            got = -shown[:, PIG_MOMENTS.index(f"{joint}_{side}_{sense}_moment")]
            want = truth[:, MODEL_MOMENTS.index(f"{joint}_{side}_flexion_moment")]
            known = result.moment_known[:, JOINTS.index(f"{joint}_{side}")]
            _, slope, rms = fit(got[known], want[known])
            cells.append(f"{rms:6.3f} {slope:5.2f}  ")
        print(f"{name:28s} " + " ".join(f"{c:>15s}" for c in cells))


def rewritten(shared: Path, out: Path, features: set[str]) -> Path:
    """``shared``'s session with ``features`` (module docstring) in ``out``."""
    out.mkdir(parents=True)
    for name in ("Static_trial.c3d", "Movement_trial.c3d"):
        c = ezc3d.c3d(str(shared / name))
        labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
        points, residuals = c["data"]["points"], c["data"]["meta_points"]["residuals"]

        def at(label, points=points, labels=labels):
            return points[:3, labels.index(label), :]

        def unit(v):
            return v / np.linalg.norm(v, axis=0, keepdims=True)

        added = {}
        for side in "RL":
            if "medial" in features:
                added[f"{side}KNM"] = 2 * at(f"{side}FEO") - at(f"{side}KNE")
                added[f"{side}MED"] = 2 * at(f"{side}TIO") - at(f"{side}ANK")
            if "clusters" in features:
                for segment, frame in (("TH", "FE"), ("SH", "TI")):
                    origin = at(f"{side}{frame}O")
                    anterior, lateral, proximal = (unit(at(f"{side}{frame}{a}") - origin) for a in "ALP")
                    first = origin + 180 * proximal + 70 * lateral  # mm
                    for k, p in enumerate((first, first + 50 * anterior, first + 60 * proximal)):
                        added[f"{side}{segment}{k + 1}"] = p
        if "sacral" in features:
            added["SACR"] = (at("RPSI") + at("LPSI")) / 2
            for label in ("RPSI", "LPSI"):
                labels[labels.index(label)] = "X" + label
        if "kad" in features and name.startswith("Static"):
            rate = float(c["parameters"]["POINT"]["RATE"]["value"][0])
            static = Markers(tuple(labels), points[:3].transpose(2, 1, 0) / 1000.0, rate)
            device = with_knee_alignment_device(static, {f"KJC{s.lower()}": at(f"{s}FEO").T / 1000.0 for s in "RL"})
            for label in ("RKAX", "RKD1", "RKD2", "LKAX", "LKD1", "LKD2"):
                added[label] = device.get(label).T * 1000.0
            for label in ("RKNE", "LKNE"):
                labels[labels.index(label)] = "X" + label
        for slot, (label, p) in zip(SLOTS, added.items(), strict=False):
            k = labels.index(slot)
            labels[k] = label
            points[:3, k, :] = p
            residuals[0, k, :] = np.where(np.isfinite(p).all(axis=0), 0.5, -1.0)
        c["parameters"]["POINT"]["LABELS"]["value"] = labels
        c["data"]["points"], c["data"]["meta_points"]["residuals"] = points, residuals
        c.write(str(out / name))
    shutil.copy(shared / "Test.vsk", out / "Test.vsk")
    return out


def shared_session(shared: Path) -> None:
    vicon = vicon_points(shared / "Movement_trial.c3d")
    stance = {s: np.nan_to_num(vicon[f"{s.upper()}GroundReactionForce"][:, 2]) > 0.5 for s in "rl"}
    rows = [(f"{j}_{s}_{'plantarflexor' if j == 'ankle' else 'extensor'}_moment_per_kg", label, c, s)
            for name, label, c, s in MOMENTS for j, side in SAGITTAL
            if name == f"{j}_{side}_{'plantarflexor' if j == 'ankle' else 'extensor'}_moment_per_kg" and side == s]
    print("\n../shared/data/pig rewritten: sagittal moments against Vicon's (r, slope, RMS N·m/kg)")
    print(f"{'features':28s} " + " ".join(f"{name.split('_moment')[0]:>25s}" for name, *_ in rows))
    root = Path(tempfile.mkdtemp(prefix="bench_pig_features_"))
    try:
        for features in ((), ("medial",), ("clusters",), ("sacral",), ("kad",), ("medial", "clusters", "sacral")):
            folder = shared if not features else rewritten(shared, root / "_".join(features), set(features))
            moments = read_csv(run_session(folder, root / ("run_" + ("_".join(features) or "as_recorded")),
                                           with_subject_yaml=True) / "joint_moments.csv")
            cells = []
            for name, label, c, s in rows:
                got = np.where(stance[s], moments[name], np.nan)
                r, slope, rms = fit(got, vicon[label][:, c] / 1000.0)
                cells.append(f"{r:5.3f} {slope:5.2f} {rms:6.3f}")
            print(f"{'+'.join(features) or 'as recorded':28s} " + " ".join(f"{c:>25s}" for c in cells))
    finally:
        shutil.rmtree(root, ignore_errors=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=ROOT.parent / "shared" / "data" / "pig")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="synthetic walks' seeds")
    args = parser.parse_args()
    for seed in args.seeds:
        synthetic(seed)
    if (args.shared / "Movement_trial.c3d").exists():
        shared_session(args.shared)
    else:
        print(f"\n(no Plug-in Gait session at {args.shared}: the shared part is left out)")


if __name__ == "__main__":
    main()
