"""gaitcli against Vicon's own Plug-in Gait outputs on a real session (``../shared/data/pig/``).

Run from the repository root: ``python benchmarks/bench_pig.py [--session yaml|vsk] [--shared PATH] [--keep DIR]
[--segment-inertias de_leva|plug_in_gait] [--pipeline FILE]``.

The session is run as a new user would: a trial folder with the movement trial, the static, the .vsk and (``yaml``,
the default) a subject.yaml holding ``marker_set: plug_in_gait``, the mass, stature and the .vsk's knee and ankle
widths, or (``vsk``) the .vsk alone describing the subject, through ``gait idyn``. Its kinematics.csv,
joint_moments.csv and joint_powers.csv are compared with the points Vicon Nexus stored in the same C3D
(``RHipAngles`` …, ``RHipMoment`` in N·mm/kg, ``RHipPower`` in W/kg in Z), frame by frame: per variable the
correlation r, the RMS difference, the mean offset (gaitcli − Vicon) and the slope of gaitcli's on Vicon's (least
squares). Angles over every frame; moments and powers over the frames where both have that foot's load (Vicon's
ground reaction of that side non-zero and gaitcli's moment known). pyCGM's angles are compared too where the package
is installed (``pip install pycgm``; not a gaitcli dependency). Prints; asserts nothing."""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SUBJECT = """mass_kg: 85
stature_m: 1.679
sex: male
marker_set: plug_in_gait
hip_joint_centre: davis
knee_width_mm: [139, 144]
ankle_width_mm: [89, 85]
"""
SIDES = (("r", "R"), ("l", "L"))
ANGLES = [("pelvis_tilt", "RPelvisAngles", 0), ("pelvis_obliquity", "RPelvisAngles", 1),
          ("pelvis_rotation", "RPelvisAngles", 2)]
for _s, _S in SIDES:
    for _j, _J in (("hip", "Hip"), ("knee", "Knee"), ("ankle", "Ankle")):
        for _c, _a in enumerate(("flexion", "inversion" if _j == "ankle" else "adduction", "rotation")):
            ANGLES.append((f"{_j}_{_s}_{_a}", f"{_S}{_J}Angles", _c))
    ANGLES.append((f"foot_{_s}_progression", f"{_S}FootProgressAngles", 2))
MOMENTS = [(f"{j}_{s}_{sense}_moment_per_kg", f"{S}{J}Moment", c, s)
           for s, S in SIDES for j, J in (("hip", "Hip"), ("knee", "Knee"), ("ankle", "Ankle"))
           for c, sense in enumerate(("plantarflexor" if j == "ankle" else "extensor",
                                      "everter" if j == "ankle" else "abductor", "external_rotator"))]
POWERS = [(f"{j}_{s}_power_W_per_kg", f"{S}{J}Power", 2, s)
          for s, S in SIDES for j, J in (("hip", "Hip"), ("knee", "Knee"), ("ankle", "Ankle"))]


def vicon_points(path: Path) -> dict[str, np.ndarray]:
    """Vicon's model outputs stored as points in the C3D: label → (frames, 3), NaN where Nexus left a gap."""
    import ezc3d

    c3d = ezc3d.c3d(str(path))
    labels = c3d["parameters"]["POINT"]["LABELS"]["value"]
    points = c3d["data"]["points"][:3].transpose(2, 1, 0)
    residuals = c3d["data"]["meta_points"]["residuals"][0].T
    out = {}
    for k, label in enumerate(labels):
        values = points[:, k].copy()
        values[residuals[:, k] < 0] = np.nan
        out[label] = values
    return out


def read_csv(path: Path) -> dict[str, np.ndarray]:
    data = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.asarray(data[name], dtype=float) for name in data.dtype.names}


def row(name: str, ours: np.ndarray, theirs: np.ndarray, mask=None) -> str:
    ok = np.isfinite(ours) & np.isfinite(theirs) & (True if mask is None else mask)
    if ok.sum() < 3:
        return f"{name:34s} {'—':>6s} {'—':>8s} {'—':>8s} {'—':>6s} {int(ok.sum()):6d}"
    d = ours[ok] - theirs[ok]
    r = np.corrcoef(ours[ok], theirs[ok])[0, 1]
    slope = np.polyfit(theirs[ok], ours[ok], 1)[0]
    return f"{name:34s} {r:6.3f} {np.sqrt(np.mean(d ** 2)):8.3f} {d.mean():8.3f} {slope:6.3f} {int(ok.sum()):6d}"


PYCGM_ANGLES = {"pelvis": 0, "hip_r": 1, "hip_l": 2, "knee_r": 3, "knee_l": 4, "ankle_r": 5, "ankle_l": 6,
                "foot_r": 7, "foot_l": 8}  # pyCGM 1.0's angle rows (19 × 3 per frame)


def pycgm_angles(shared: Path) -> dict[str, np.ndarray] | None:
    """pyCGM 1.0's angles of the session in gaitcli's columns and signs (deg), or None without the package. Its
    pelvis rotation is about the lab's axes, not the direction of progression, and is left out."""
    import contextlib
    import io

    with contextlib.redirect_stdout(io.StringIO()):
        try:
            from pyCGM_Single import pycgmCalc, pycgmIO, pycgmStatic
        except ImportError:
            return None
        motion = pycgmIO.loadData(str(shared / "Movement_trial.c3d"))
        static = pycgmIO.loadData(str(shared / "Static_trial.c3d"))
        vsk = pycgmIO.createVskDataDict(*pycgmIO.loadVSK(str(shared / "Test.vsk")))
        calibrated = pycgmStatic.getStatic(static, vsk, flat_foot=False)
        rows = np.asarray(pycgmCalc.calcAngles(motion, vsk=calibrated, splitAnglesAxis=True, formatData=False)[0])
    a = rows.T.reshape(rows.shape[1], -1, 3)
    p = a[:, PYCGM_ANGLES["pelvis"]]
    out = {"pelvis_tilt": -p[:, 0], "pelvis_obliquity": p[:, 1]}
    for s in ("r", "l"):
        for joint in ("hip", "knee", "ankle"):
            j = a[:, PYCGM_ANGLES[f"{joint}_{s}"]]
            frontal = "inversion" if joint == "ankle" else "adduction"
            out.update({f"{joint}_{s}_flexion": j[:, 0], f"{joint}_{s}_{frontal}": j[:, 1],
                        f"{joint}_{s}_rotation": j[:, 2]})
        out[f"foot_{s}_progression"] = -a[:, PYCGM_ANGLES[f"foot_{s}"], 2]
    return out


def run_session(shared: Path, root: Path, *, with_subject_yaml: bool, extra: str = "",
                pipeline: Path | None = None) -> Path:
    """``gait idyn`` on a folder holding the movement trial, the static and the .vsk (and ``SUBJECT`` as
    subject.yaml when ``with_subject_yaml``); its idyn output folder."""
    trial = root / ("pig_yaml" if with_subject_yaml else "pig_vsk")
    trial.mkdir(parents=True, exist_ok=True)
    shutil.copy(shared / "Movement_trial.c3d", trial / "trial.c3d")
    shutil.copy(shared / "Static_trial.c3d", trial / "static.c3d")
    shutil.copy(shared / "Test.vsk", trial / "Test.vsk")
    if with_subject_yaml:
        (trial / "subject.yaml").write_text(SUBJECT + extra)
    run = subprocess.run([sys.executable, "-m", "gaitcli", "-q", "idyn", str(trial), "--no-plots"]
                         + (["--pipeline", str(pipeline)] if pipeline else []), capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"gait idyn failed ({run.returncode}): {run.stderr.strip()}")
    return trial / "gait_out" / "idyn"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=ROOT.parent / "shared" / "data" / "pig")
    parser.add_argument("--keep", type=Path, default=None, help="run in this folder and keep it")
    parser.add_argument("--session", choices=("yaml", "vsk"), default="yaml",
                        help="yaml: subject.yaml + .vsk (default); vsk: the .vsk alone describes the subject")
    parser.add_argument("--segment-inertias", choices=("de_leva", "plug_in_gait"), default=None,
                        help="subject.yaml's segment_inertias (default: by the marker set, Plug-in Gait's)")
    parser.add_argument("--pipeline", type=Path, default=None, help="a pipeline YAML for gait idyn (filter settings)")
    args = parser.parse_args()
    if not (args.shared / "Movement_trial.c3d").exists():
        sys.exit(f"no Plug-in Gait session at {args.shared}")
    root = args.keep or Path(tempfile.mkdtemp(prefix="bench_pig_"))
    extra = f"segment_inertias: {args.segment_inertias}\n" if args.segment_inertias else ""
    out = run_session(args.shared, root, with_subject_yaml=args.session == "yaml", extra=extra,
                      pipeline=args.pipeline and args.pipeline.resolve())
    kin, mom, power = (read_csv(out / f"{n}.csv") for n in ("kinematics", "joint_moments", "joint_powers"))
    vicon = vicon_points(args.shared / "Movement_trial.c3d")
    pycgm = pycgm_angles(args.shared)
    stance = {s: np.nan_to_num(vicon[f"{S}GroundReactionForce"][:, 2]) > 0.5 for s, S in SIDES}
    print(f"session: {'subject.yaml + Test.vsk' if args.session == 'yaml' else 'Test.vsk alone'}")
    header = f"{'variable (gaitcli vs Vicon)':34s} {'r':>6s} {'RMS':>8s} {'offset':>8s} {'slope':>6s} {'frames':>6s}"
    print("Angles (deg), every frame\n" + header + ("   | vs pyCGM: r, RMS, offset" if pycgm else ""))
    for name, label, c in ANGLES:  # the ankle inversion is Vicon's AnkleAngles Y as written (kinematics.conventions)
        line = row(name, kin[name], vicon[label][:, c])
        if pycgm and name in pycgm:
            line += "   |" + row("", kin[name], pycgm[name])[34:-7]
        print(line)
    if pycgm is None:
        print("(pyCGM not installed: pip install pycgm adds its angles)")
    print("\nMoments (N·m/kg), frames where both have the foot's load\n" + header)
    for name, label, c, s in MOMENTS:
        print(row(name, mom[name], vicon[label][:, c] / 1000.0, stance[s]))
    print("\nPowers (W/kg, total), frames where both have the foot's load\n" + header)
    for name, label, c, s in POWERS:
        print(row(name, power[name], vicon[label][:, c], stance[s]))
    if args.keep is None:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
