"""``gait idyn --export opensim --export c3d`` on a copy of the bundled normal trial: the exports read back to
what idyn's tables say (OpenSim's axes: (x, z, −y) of the model's; the C3D's added points in N·mm/kg and deg),
and the C3D's own markers stay as they were."""

from __future__ import annotations

import ezc3d
import h5py
import numpy as np
import pandas as pd
import pytest

from gaitcli.io.c3d import read_c3d
from gaitcli.io.opensim import read_motion, read_trc
from gaitcli.kinematics.model import JOINTS, MOMENTS

from .conftest import copy_sample, gait
from .opensim_tools import largest_differences, opensim_trc_labels


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    trial = copy_sample("normal", root / "normal")
    r = gait("idyn", trial, "--export", "opensim", "--export", "c3d", "--no-plots", cwd=root)
    assert r.returncode == 0, r.describe()
    return trial


def test_the_opensim_files_read_back_to_idyns_tables(exported):
    out = exported / "gait_out"
    folder = out / "export" / "opensim"
    _, labels, _, markers = read_trc(folder / "markers.trc")
    assert sorted(labels) == sorted(read_c3d(exported / "trial.c3d").markers.labels)  # the lab's own
    filtered = pd.read_csv(out / "filter" / "markers_filtered.csv")
    lab = labels[0]
    # the CSV: 6 significant digits
    np.testing.assert_allclose(markers[:, 0, 0], 1000 * filtered[f"{lab}_x_m"], atol=0.01)
    np.testing.assert_allclose(markers[:, 0, 1], 1000 * filtered[f"{lab}_z_m"], atol=0.01)  # y up
    np.testing.assert_allclose(markers[:, 0, 2], -1000 * filtered[f"{lab}_y_m"], atol=0.01)  # z right
    header, motion = read_motion(folder / "coordinates.mot")
    assert header["inDegrees"] == "yes" and header["nColumns"] == "28"
    clinical = pd.read_csv(out / "idyn" / "coordinates.csv")  # the 27 coordinates, clinical signs
    for name, theirs, sign in (("hip_r_flexion", "hip_flexion_r", 1), ("knee_l_flexion", "knee_angle_l", 1),
                               ("ankle_l_flexion", "ankle_angle_l", 1), ("hip_l_adduction", "hip_adduction_l", 1),
                               ("ankle_r_adduction", "subtalar_angle_r", 1), ("pelvis_z", "pelvis_ty", 1),
                               ("pelvis_y", "pelvis_tz", -1), ("pelvis_rot_y", "pelvis_tilt", -1),
                               ("lumbar_flexion", "lumbar_extension", -1)):  # deg; m
        np.testing.assert_allclose(motion[theirs], sign * clinical[name], rtol=1e-5, atol=1e-6)
    header, moments = read_motion(folder / "joint_moments.sto")
    with h5py.File(out / "idyn" / "idyn.h5", "r") as h5:  # the rotation axis is the shank's own z: Q = τ_z
        knee = h5["joint_moments_clinical"][:, MOMENTS.index("knee_r_rotation_moment")]
        knee[~h5["joint_moments_known"][:, JOINTS.index("knee_r")].astype(bool)] = np.nan
    assert header["inDegrees"] == "no" and header["nColumns"] == "28"
    np.testing.assert_allclose(moments["knee_rotation_r_moment"], knee, rtol=1e-5, atol=1e-6, equal_nan=True)
    _, grf = read_motion(folder / "grf.mot")
    filter_grf = pd.read_csv(out / "filter" / "grf.csv")
    np.testing.assert_allclose(grf["r_ground_force_vy"], filter_grf["foot_r_force_z_N"].fillna(0), atol=1e-3)
    xml = (folder / "external_loads.xml").read_text()
    assert "<applied_to_body>calcn_r</applied_to_body>" in xml and "<force_identifier>l_ground_force_v<" in xml
    assert '<Body name="calcn_r">' in (folder / "model.osim").read_text()


def test_opensims_inverse_dynamics_on_the_export_gives_gaitclis_moments(exported, tmp_path):
    """OpenSim's InverseDynamicsTool on model.osim + coordinates.mot + external_loads.xml: gaitcli's generalized
    forces of the same motion to 1e-3 N·m (and N), every frame, all 27 coordinates (tests/cli/opensim_tools.py)."""
    differences = largest_differences(exported / "gait_out", tmp_path)
    assert len(differences) == 27
    assert max(differences.values()) < 1e-3, differences


def test_opensim_reads_the_trc_under_the_labs_labels(exported, tmp_path):
    folder = exported / "gait_out" / "export" / "opensim"
    labels, rows = opensim_trc_labels(folder / "markers.trc", tmp_path)
    assert sorted(labels) == sorted(read_c3d(exported / "trial.c3d").markers.labels)
    assert rows == len(read_motion(folder / "coordinates.mot")[1]["time"])


def test_the_c3d_copy_carries_angles_and_moments_and_the_markers_as_they_were(exported):
    out = exported / "gait_out"
    copy = out / "export" / "normal.c3d"
    c = ezc3d.c3d(str(copy))
    labels = list(c["parameters"]["POINT"]["LABELS"]["value"])
    original = ezc3d.c3d(str(exported / "trial.c3d"))
    n = len(original["parameters"]["POINT"]["LABELS"]["value"])
    np.testing.assert_array_equal(c["data"]["points"][:, :n], original["data"]["points"])
    assert c["parameters"]["POINT"]["MOMENT_UNITS"]["value"] == ["Nmm/kg"]
    kinematics = pd.read_csv(out / "idyn" / "kinematics.csv")
    moments = pd.read_csv(out / "idyn" / "joint_moments.csv")
    knee = c["data"]["points"][:3, labels.index("RKneeAngles")]
    np.testing.assert_allclose(knee[0], kinematics["knee_r_flexion"], rtol=1e-6, atol=1e-4)  # float32
    ankle = c["data"]["points"][:3, labels.index("LAnkleMoment")]
    residual = c["data"]["meta_points"]["residuals"][0, labels.index("LAnkleMoment")]
    want = 1000 * moments["ankle_l_plantarflexor_moment_per_kg"].to_numpy()
    known = np.isfinite(want)
    np.testing.assert_allclose(ankle[0, known], want[known], rtol=1e-5, atol=1e-3)
    assert np.all(residual[~known] < 0) and np.all(residual[known] >= 0)
    again, before = read_c3d(copy), read_c3d(exported / "trial.c3d")  # the project's reader takes the copy too,
    assert again.markers.labels == before.markers.labels  # and leaves the model outputs out of the markers
    np.testing.assert_array_equal(again.markers.positions_m, before.markers.positions_m)


def test_the_c3d_copy_carries_the_events_the_filter_used(exported):
    """The sample trial has no EVENT group: its detected events go into the copy as Vicon Nexus writes them."""
    out = exported / "gait_out"
    events = pd.read_csv(out / "filter" / "events.csv")
    c = ezc3d.c3d(str(out / "export" / "normal.c3d"))
    group = c["parameters"]["EVENT"]
    assert group["USED"]["value"][0] == len(events) > 0
    assert group["LABELS"]["value"] == [{"heel_strike": "Foot Strike", "toe_off": "Foot Off"}[k] for k in events.event]
    assert group["CONTEXTS"]["value"] == [{"r": "Right", "l": "Left"}[s] for s in events.side]
    times = np.asarray(group["TIMES"]["value"])
    start = c["header"]["points"]["first_frame"] / c["parameters"]["POINT"]["RATE"]["value"][0]
    np.testing.assert_allclose(60 * times[0] + times[1] - start, events.time_s, atol=1e-5)
    again = read_c3d(out / "export" / "normal.c3d").events  # gaitcli reads them back as the file's own
    np.testing.assert_allclose(again.time_s, events.time_s, atol=1e-5)
    assert set(again.source) == {"file"}
