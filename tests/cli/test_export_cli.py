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
    filtered = pd.read_csv(out / "filter" / "markers_filtered.csv")
    lab = labels[0]
    # the CSV: 6 significant digits
    np.testing.assert_allclose(markers[:, 0, 0], 1000 * filtered[f"{lab}_x_m"], atol=0.01)
    np.testing.assert_allclose(markers[:, 0, 1], 1000 * filtered[f"{lab}_z_m"], atol=0.01)  # y up
    np.testing.assert_allclose(markers[:, 0, 2], -1000 * filtered[f"{lab}_y_m"], atol=0.01)  # z right
    header, motion = read_motion(folder / "coordinates.mot")
    assert header["inDegrees"] == "yes" and header["nColumns"] == "28"
    kinematics = pd.read_csv(out / "idyn" / "coordinates.csv")  # OpenSim's coordinates: the model's 27
    for name in ("hip_r_flexion", "knee_l_flexion", "pelvis_x"):  # deg; m
        np.testing.assert_allclose(motion[name], kinematics[name], rtol=1e-5, atol=1e-6)
    header, moments = read_motion(folder / "joint_moments.sto")
    with h5py.File(out / "idyn" / "idyn.h5", "r") as h5:  # the model's generalized forces' convention
        knee = h5["joint_moments_clinical"][:, MOMENTS.index("knee_r_flexion_moment")]
        knee[~h5["joint_moments_known"][:, JOINTS.index("knee_r")].astype(bool)] = np.nan
    assert header["inDegrees"] == "no"
    np.testing.assert_allclose(moments["knee_r_flexion_moment"], knee, rtol=1e-5, atol=1e-6, equal_nan=True)
    _, grf = read_motion(folder / "grf.mot")
    filter_grf = pd.read_csv(out / "filter" / "grf.csv")
    np.testing.assert_allclose(grf["r_ground_force_vy"], filter_grf["foot_r_force_z_N"].fillna(0), atol=1e-3)
    xml = (folder / "external_loads.xml").read_text()
    assert "<applied_to_body>calcn_r</applied_to_body>" in xml and "<force_identifier>l_ground_force_v<" in xml


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
