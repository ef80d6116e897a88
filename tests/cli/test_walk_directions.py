"""A Plug-in Gait walk without a static, along the lab's +X, −X, +Y and −Y (issue 52, item 3): the sagittal
angles agree with the synthetic truth whichever way the lab's axes lie; a walk whose right and left labels are
swapped (every angle mirrored: the knee hyperextended, the ankle near −190°) is exit 2, never a silent answer.
"""

from __future__ import annotations

import shutil

import ezc3d
import numpy as np
import pandas as pd
import pytest

from .conftest import gait, gait_many

SAGITTAL = [f"{joint}_{side}_flexion" for side in "rl" for joint in ("hip", "knee", "ankle")]


def _rewritten(source, target, *, turn_deg: float = 0.0, swap_sides: bool = False):
    """``source``'s trial.c3d turned about the vertical (markers and plate corners) or with R/L labels swapped,
    with its subject.yaml and no static, in ``target``."""
    target.mkdir()
    c = ezc3d.c3d(str(source / "trial.c3d"))
    t = np.radians(turn_deg)
    turn = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])
    points = c["data"]["points"]
    points[:3] = np.einsum("ij,jnf->inf", turn, points[:3])
    c["data"]["points"] = points
    corners = np.asarray(c["parameters"]["FORCE_PLATFORM"]["CORNERS"]["value"], float)
    c["parameters"]["FORCE_PLATFORM"]["CORNERS"]["value"] = np.einsum("ij,jkp->ikp", turn, corners)
    if swap_sides:
        other = {"R": "L", "L": "R"}
        c["parameters"]["POINT"]["LABELS"]["value"] = [other[s[0]] + s[1:] if s[:1] in other else s
                                                      for s in c["parameters"]["POINT"]["LABELS"]["value"]]
    c.write(str(target / "trial.c3d"))
    shutil.copy(source / "subject.yaml", target / "subject.yaml")
    return target


@pytest.fixture(scope="module")
def walks(tmp_path_factory):
    root = tmp_path_factory.mktemp("directions")
    made = gait("synth", "--marker-set", "plug_in_gait", "--strides", "2", "--seed", "3", root / "synth", cwd=root)
    assert made.returncode == 0, made.describe()
    folders = {f"{deg}": _rewritten(root / "synth", root / f"turn{deg}", turn_deg=deg) for deg in (0, 90, 180, 270)}
    folders["swapped"] = _rewritten(root / "synth", root / "swapped", turn_deg=90, swap_sides=True)
    runs = gait_many({k: (("idyn", folder, "--no-plots"), root) for k, folder in folders.items()}, workers=2)
    return root, folders, runs


@pytest.mark.parametrize("turn", ["0", "90", "180", "270"])
def test_a_walk_without_static_agrees_with_the_truth_along_every_lab_axis(walks, turn):
    root, folders, runs = walks
    assert runs[turn].returncode == 0, runs[turn].describe()
    ours = pd.read_csv(folders[turn] / "gait_out" / "idyn" / "kinematics.csv")
    truth = pd.read_csv(root / "synth" / "truth" / "kinematics.csv")
    for name in SAGITTAL:
        expected = np.interp(ours.time_s, truth.time_s, truth[name])
        got = ours[name].to_numpy()
        assert np.corrcoef(got, expected)[0, 1] >= 0.95, name
        assert np.sqrt(np.mean((got - expected) ** 2)) <= 8.0, name


def test_a_walk_with_its_sides_swapped_is_exit_2(walks):
    _, folders, runs = walks
    r = runs["swapped"]
    assert r.returncode == 2, r.describe()
    assert "the right ASIS marker lies left of the left one in 100 % of the frames" in r.stderr
    assert "Traceback" not in r.stderr
    assert not (folders["swapped"] / "gait_out" / "idyn").exists()


@pytest.mark.shared
def test_the_shared_walk_turned_without_its_static_agrees_with_vicon(shared_pig_dir, tmp_path):
    """../shared/data/pig's walk (along −X) turned to +Y and −Y, without its static: hip and knee flexion within
    8° RMS of Vicon's (r ≥ 0.95); the ankle's shape too (r ≥ 0.95; its offset is Vicon's static foot offsets,
    which a walk alone does not give)."""
    source = tmp_path / "source"
    source.mkdir()
    shutil.copy(shared_pig_dir / "Movement_trial.c3d", source / "trial.c3d")
    (source / "subject.yaml").write_text("mass_kg: 85\nstature_m: 1.679\nsex: male\nmarker_set: plug_in_gait\n"
                                         "hip_joint_centre: davis\nknee_width_mm: [139, 144]\n"
                                         "ankle_width_mm: [89, 85]\n")
    folders = {deg: _rewritten(source, tmp_path / f"turn{deg}", turn_deg=deg) for deg in (90, 270)}
    runs = gait_many({deg: (("idyn", folder, "--no-plots"), tmp_path) for deg, folder in folders.items()}, workers=2)
    c = ezc3d.c3d(str(shared_pig_dir / "Movement_trial.c3d"))
    labels = c["parameters"]["POINT"]["LABELS"]["value"]
    vicon = c["data"]["points"][0]  # the x component: flexion
    for deg, folder in folders.items():
        assert runs[deg].returncode == 0, runs[deg].describe()
        ours = pd.read_csv(folder / "gait_out" / "idyn" / "kinematics.csv")
        for name in SAGITTAL:
            side, joint = name.split("_")[1].upper(), name.split("_")[0].capitalize()
            theirs = vicon[labels.index(f"{side}{joint}Angles")]
            got = ours[name].to_numpy()
            seen = np.isfinite(got) & np.isfinite(theirs)
            assert np.corrcoef(got[seen], theirs[seen])[0, 1] >= 0.95, (deg, name)
            if joint != "Ankle":
                assert np.sqrt(np.mean((got[seen] - theirs[seen]) ** 2)) <= 8.0, (deg, name)
