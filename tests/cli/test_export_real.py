"""``gait idyn --export c3d --export opensim`` on real trials: Vicon's Plug-in Gait stair session
(``../shared/data/pig``, whose C3D already holds Nexus's own LKneeAngles, RHipMoment, … and 239 points) and
walking5.c3d (Vicon, Cleveland-like markers, no other CLI test runs it). Every other real C3D in ../shared/data is
exported at the writer's level by tests/io/test_c3d_write_real.py; walking2 and Qualisys by their own CLI tests.
BTS.c3d and Gait.c3d stop before the export (exit 2: one sacral marker under a label the presets do not know),
the c3d.org files have no anatomical markers.

The stair session's copy holds each of Vicon's 22 lower-body names once, with gaitcli's values (the tables'),
Vicon's units (POINT:ANGLE_UNITS deg, MOMENT_UNITS Nmm/kg, POWER_UNITS W), Nexus's other outputs untouched, the
events the filter used, and the run says which points it replaced.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest

from gaitcli.io.opensim import read_motion, read_trc
from tests.conftest import REPO
from tests.opensim_runner import opensim_installed

from .conftest import EXPORTS, Result, build_once, gait
from .opensim_tools import largest_differences, opensim_trc_labels

pytestmark = pytest.mark.shared
VICON = [f"{side}{name}" for side in "RL" for name in ("PelvisAngles", "FootProgressAngles", "HipAngles",
                                                       "KneeAngles", "AnkleAngles", "HipMoment", "KneeMoment",
                                                       "AnkleMoment", "HipPower", "KneePower", "AnklePower")]


def _build(shared: Path, root: Path) -> dict:
    walking5 = root / "walking5"
    walking5.mkdir()
    shutil.copy(shared / "c3d" / "walking5.c3d", walking5 / "trial.c3d")
    shutil.copy(REPO / "docs" / "examples" / "walking2" / "subject.yaml", walking5)
    return {"walking5": gait("idyn", walking5, *EXPORTS, cwd=root).to_json()}


@pytest.fixture(scope="module")
def exported(shared_c3d_dir, stair_sessions, tmp_path_factory):
    """{trial: (its folder, Result)}: walking5 run here, the stair session's .vsk-only run shared
    (tests/cli/conftest.py ``stair_sessions``)."""
    root, record = build_once(tmp_path_factory, "cli_export_real",
                              lambda root: _build(shared_c3d_dir.parent, root))
    stair_root, stair = stair_sessions
    return {"walking5": (root / "walking5", Result.from_json(record["walking5"])),
            "pig": (stair_root / "pig", stair["pig"])}


def _labels(c) -> list[str]:
    point = c["parameters"]["POINT"]
    return [lab.strip() for lab in point["LABELS"]["value"] + point.get("LABELS2", {}).get("value", [])]


@pytest.mark.parametrize("trial", ["pig", "walking5"])
def test_both_exports_write_files_that_read_back(exported, trial):
    folder, run = exported[trial]
    assert run.returncode == 0, run.describe()
    out = folder / "gait_out"
    c = ezc3d.c3d(str(out / "export" / f"{trial}.c3d"))
    labels = _labels(c)
    assert len(labels) == c["data"]["points"].shape[1] == len(set(labels))
    assert set(VICON) <= set(labels)
    kinematics = pd.read_csv(out / "idyn" / "kinematics.csv")
    assert len(kinematics) == c["data"]["points"].shape[2]
    opensim = out / "export" / "opensim"
    trc = read_trc(opensim / "markers.trc")
    assert trc is not None
    for name in ("coordinates.mot", "grf.mot", "joint_moments.sto"):
        table = read_motion(opensim / name)
        assert table is not None
    assert (opensim / "external_loads.xml").read_text().count("<ExternalForce ") == 2


def test_the_stair_sessions_own_vicon_points_are_replaced_and_said(exported, shared_pig_dir):
    folder, run = exported["pig"]
    assert run.returncode == 0, run.describe()
    (said,) = [line for line in run.stderr_lines if "replaced" in line]
    assert said.startswith("gait: warning: trial.c3d: its own points ") and all(lab in said for lab in VICON)
    out = folder / "gait_out"
    c = ezc3d.c3d(str(out / "export" / "pig.c3d"))
    vicon = ezc3d.c3d(str(shared_pig_dir / "Movement_trial.c3d"))
    labels, own = _labels(c), _labels(vicon)
    assert labels == own  # replaced in place: 239 points, one label each
    point = c["parameters"]["POINT"]
    assert (point["ANGLE_UNITS"]["value"], point["MOMENT_UNITS"]["value"], point["POWER_UNITS"]["value"]) == \
        (["deg"], ["Nmm/kg"], ["W"])
    assert {"RNeckAngles", "RKneeAngles"} <= set(point["ANGLES"]["value"])  # Nexus's list kept, extended
    data, before = c["data"]["points"][:3], vicon["data"]["points"][:3]
    kinematics = pd.read_csv(out / "idyn" / "kinematics.csv")
    moments = pd.read_csv(out / "idyn" / "joint_moments.csv")
    knee = data[:, labels.index("RKneeAngles")]
    np.testing.assert_allclose(knee[0], kinematics["knee_r_flexion"], rtol=1e-5, atol=1e-3)  # float32
    assert np.nanmax(np.abs(knee[0] - before[0, own.index("RKneeAngles")])) > 0.1  # not Nexus's any more
    hip = data[:, labels.index("LHipMoment")]
    want = 1000.0 * moments["hip_l_extensor_moment_per_kg"].to_numpy()
    residual = c["data"]["meta_points"]["residuals"][0, labels.index("LHipMoment")]
    known = np.isfinite(want)
    np.testing.assert_allclose(hip[0, known], want[known], rtol=1e-5, atol=1e-2)
    assert np.all(residual[~known] < 0)
    for other in ("RNeckAngles", "RAbsAnkleAngle", "RGroundReactionForce", "LHipForce"):  # Nexus's, untouched
        np.testing.assert_array_equal(data[:, labels.index(other)], before[:, own.index(other)])
    events = pd.read_csv(out / "filter" / "events.csv")
    assert set(events.source) <= {"plate", "kinematics"}  # the file's EVENT group is empty: the events detected
    group = c["parameters"]["EVENT"]
    assert group["USED"]["value"][0] == len(events) > 0
    assert group["LABELS"]["value"] == [{"heel_strike": "Foot Strike", "toe_off": "Foot Off"}[k] for k in events.event]
    assert group["CONTEXTS"]["value"] == [{"r": "Right", "l": "Left"}[s] for s in events.side]
    start = c["header"]["points"]["first_frame"] / point["RATE"]["value"][0]
    times = np.asarray(group["TIMES"]["value"])
    np.testing.assert_allclose(60 * times[0] + times[1] - start, events.time_s, atol=1e-5)


#: the stair session's C3D points that are no marker: Vicon's unlabelled trajectories and Plug-in Gait's virtual
#: points (segment origins and axes, joint centres, the centre of mass), as its POINT:LABELS list them
STAIR_UNLABELLED = tuple(f"*{k}" for k in range(115, 157))
STAIR_VIRTUAL = (tuple(f"{seg}{p}" for seg in ("PEL", "HED", "TRX") for p in "OALP")
                 + tuple(f"{s}{seg}{p}" for s in "LR" for seg in ("FE", "TI", "FO", "TO", "CL", "HU", "RA", "HN")
                         for p in "OALP") + ("CentreOfMass", "CentreOfMassFloor"))


def test_the_stair_sessions_trc_keeps_the_labs_markers_under_their_labels_and_says_what_it_left_out(exported,
                                                                                                  tmp_path):
    folder, run = exported["pig"]
    assert run.returncode == 0, run.describe()
    c3d = ezc3d.c3d(str(folder / "trial.c3d"))
    point = c3d["parameters"]["POINT"]
    outputs = {lab for group in ("ANGLES", "FORCES", "MOMENTS", "POWERS") for lab in point[group]["value"]}
    labels = [lab for lab in _labels(c3d) if lab not in outputs]
    assert set(STAIR_UNLABELLED) | set(STAIR_VIRTUAL) <= set(labels)
    markers = [lab for lab in labels if lab not in STAIR_UNLABELLED + STAIR_VIRTUAL]
    _, written, _, positions = read_trc(folder / "gait_out" / "export" / "opensim" / "markers.trc")
    assert sorted(written) == sorted(markers) and {"RASI", "RKNE", "RTOE", "LBHD"} <= set(written)
    (said,) = [line for line in run.stdout.splitlines() + run.stderr_lines if "left out" in line]
    assert f"{len(markers)} markers under the lab's labels" in said
    assert f"left out {len(STAIR_UNLABELLED)} unlabelled (*115" in said and f"{len(STAIR_VIRTUAL)} virtual" in said
    raw = c3d["data"]["points"][:3, labels.index("RASI")]  # mm, lab axes; the .trc's filtered, in OpenSim's
    filtered = positions[:, written.index("RASI")]
    assert np.nanmax(np.abs(np.linalg.norm(filtered, axis=1) - np.linalg.norm(raw.T, axis=1))) < 5.0
    if opensim_installed():
        trc = folder / "gait_out" / "export" / "opensim" / "markers.trc"
        assert opensim_trc_labels(trc, tmp_path)[0] == list(written)


def test_opensims_inverse_dynamics_on_the_stair_sessions_export_gives_gaitclis_moments(exported, tmp_path):
    """As tests/cli/test_export_cli.py's on the synthetic walk: all 27 generalized forces to 1e-3 N·m (and N)."""
    folder, run = exported["pig"]
    assert run.returncode == 0, run.describe()
    differences = largest_differences(folder / "gait_out", tmp_path)
    assert max(differences.values()) < 1e-3, differences
