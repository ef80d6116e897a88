"""gaitcli against Vicon's own Plug-in Gait outputs on a real session (``../shared/data/pig/``).

Run from the repository root: ``python benchmarks/bench_pig.py [--shared PATH] [--keep DIR]``.

The session is run as a new user would: a trial folder with the movement trial, the static and a subject.yaml
holding ``marker_set: plug_in_gait``, the mass, stature and the .vsk's knee and ankle widths (the leg lengths,
ASIS distances and offsets come from the C3D's PROCESSING group), through ``gait idyn``. Its kinematics.csv,
joint_moments.csv and joint_powers.csv are compared with the points Vicon Nexus stored in the same C3D
(``RHipAngles`` …, ``RHipMoment`` in N·mm/kg, ``RHipPower`` in W/kg in Z), frame by frame: per variable the
correlation r, the RMS difference and the mean offset (gaitcli − Vicon). Angles over every frame; moments and
powers over the frames where both have that foot's load (Vicon's ground reaction of that side non-zero and
gaitcli's moment known). ``--pycgm`` adds pyCGM's angles where the package is installed. Prints; asserts nothing.
"""

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
        return f"{name:34s} {'—':>6s} {'—':>8s} {'—':>8s} {int(ok.sum()):6d}"
    d = ours[ok] - theirs[ok]
    r = np.corrcoef(ours[ok], theirs[ok])[0, 1]
    return f"{name:34s} {r:6.3f} {np.sqrt(np.mean(d ** 2)):8.3f} {d.mean():8.3f} {int(ok.sum()):6d}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=ROOT.parent / "shared" / "data" / "pig")
    parser.add_argument("--keep", type=Path, default=None, help="run in this folder and keep it")
    args = parser.parse_args()
    if not (args.shared / "Movement_trial.c3d").exists():
        sys.exit(f"no Plug-in Gait session at {args.shared}")
    root = args.keep or Path(tempfile.mkdtemp(prefix="bench_pig_"))
    trial = root / "pig"
    trial.mkdir(parents=True, exist_ok=True)
    shutil.copy(args.shared / "Movement_trial.c3d", trial / "trial.c3d")
    shutil.copy(args.shared / "Static_trial.c3d", trial / "static.c3d")
    (trial / "subject.yaml").write_text(SUBJECT)
    run = subprocess.run([sys.executable, "-m", "gaitcli.cli", "-q", "idyn", str(trial), "--no-plots"],
                         capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit(f"gait idyn failed ({run.returncode}): {run.stderr.strip()}")
    out = trial / "gait_out" / "idyn"
    kin, mom, power = (read_csv(out / f"{n}.csv") for n in ("kinematics", "joint_moments", "joint_powers"))
    vicon = vicon_points(args.shared / "Movement_trial.c3d")
    stance = {s: np.nan_to_num(vicon[f"{S}GroundReactionForce"][:, 2]) > 0.5 for s, S in SIDES}
    header = f"{'variable (gaitcli vs Vicon)':34s} {'r':>6s} {'RMS':>8s} {'offset':>8s} {'frames':>6s}"
    print("Angles (deg), every frame\n" + header)
    for name, label, c in ANGLES:  # Vicon's AnkleAngles Y turns about the toe → heel axis: −inversion
        print(row(name, kin[name], (-1.0 if name.endswith("inversion") else 1.0) * vicon[label][:, c]))
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
