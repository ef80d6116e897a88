"""Static calibration: body parameters, clusters, locking, missing markers, disturbances."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gaitcli.core.recording import Markers
from gaitcli.errors import GaitWarning, InputError
from gaitcli.kinematics import joint_centres as jcm
from gaitcli.kinematics.calibration import calibrate, least_flexed_frames, static_landmarks
from gaitcli.kinematics.markerset import landmarks_to_markers, marker_set, standing_template
from gaitcli.kinematics.model import BODIES, JOINT_CHILD, JOINT_PARENT, JOINTS
from gaitcli.kinematics.rotations import cardan_xyz_to_matrix, rot_z

SUBJECT = dict(mass_kg=73.0, stature_m=1.792)


def _static(**changes):
    t = standing_template(1.792)
    for name, value in changes.items():
        if value is None:
            t.pop(name)
        else:
            t[name] = value
    return landmarks_to_markers(t)


@pytest.fixture(scope="module")
def cal():
    return calibrate(_static(), **SUBJECT)


def test_body_parameters_are_complete_and_consistent(cal):
    body = cal.body
    assert body.mass_kg.shape == (8,) and body.inertia_kgm2.shape == (8, 3, 3)
    assert body.joint_in_parent_m.shape == (7, 3) and body.joint_in_child_m.shape == (7, 3)
    assert body.total_mass_kg == pytest.approx(73.0, abs=1e-12)
    np.testing.assert_allclose(body.inertia_kgm2, np.swapaxes(body.inertia_kgm2, 1, 2))
    assert np.all(np.linalg.eigvalsh(body.inertia_kgm2) > 0)
    # the static posture is the zero of the reference-frame coordinates: every joint centre is
    # placed at the same point by parent and child with identity rotations
    for j, name in enumerate(JOINTS):
        by_parent = cal.com_m[JOINT_PARENT[j]] + body.joint_in_parent_m[j]
        by_child = cal.com_m[JOINT_CHILD[j]] + body.joint_in_child_m[j]
        np.testing.assert_allclose(by_parent, by_child, atol=1e-15, err_msg=name)
    centres = cal.joint_centres_m
    np.testing.assert_allclose(cal.com_m[0] + body.joint_in_parent_m[1], centres["HJCr"], atol=1e-15)
    # Table A.4 pelvis geometry: c1 = 0.092 m (CoM to lumbar joint), d2 = 0.058 m (CoM above the hips)
    assert body.joint_in_parent_m[0] == pytest.approx([0, 0, 0.092], abs=0.0005)
    assert -body.joint_in_parent_m[1, 2] == pytest.approx(0.058, abs=0.0005)
    assert body.joint_in_child_m[0] == pytest.approx([0, 0, -0.269], abs=0.0005)  # c2


def test_coms_lie_on_joint_centre_lines_at_de_leva_fractions(cal):
    c = cal.joint_centres_m
    for s in "rl":
        thigh = cal.com_m[BODIES.index(f"thigh_{s}")]
        np.testing.assert_allclose(thigh, c[f"HJC{s}"] + 0.4095 * (c[f"KJC{s}"] - c[f"HJC{s}"]), atol=1e-15)
        shank = cal.com_m[BODIES.index(f"shank_{s}")]
        np.testing.assert_allclose(shank, c[f"KJC{s}"] + 0.4395 * (c[f"AJC{s}"] - c[f"KJC{s}"]), atol=1e-15)
        assert cal.body.segment_length_m[f"thigh_{s}"] == pytest.approx(np.linalg.norm(c[f"HJC{s}"] - c[f"KJC{s}"]))
        foot = cal.com_m[BODIES.index(f"foot_{s}")]
        heel = cal.static_landmarks_m[f"CA{s}"]
        assert np.linalg.norm(foot - heel) == pytest.approx(0.4415 * 258.1e-3 * 1.792 / 1.741)


def test_clusters_reproduce_the_static_markers(cal):
    for b in BODIES:
        i = BODIES.index(b)
        assert len(cal.tracking_landmarks[b]) >= 3
        for name in cal.tracking_landmarks[b]:
            np.testing.assert_allclose(cal.com_m[i] + cal.landmarks_in_body_m[b][name], cal.static_landmarks_m[name],
                                       atol=1e-15)
    assert cal.locked == ()
    assert all(cal.anatomical_from_landmarks)
    arrays, labels = cal.markers_in_body()
    np.testing.assert_array_equal(arrays[2][labels[2].index("GTr")], cal.landmarks_in_body_m["thigh_r"]["GTr"])
    C = cal.reference_to_anatomical
    np.testing.assert_allclose(C @ np.swapaxes(C, 1, 2), np.broadcast_to(np.eye(3), C.shape), atol=1e-14)


def test_inertia_is_rotated_into_body_axes():
    t = standing_template(1.792)
    # swing the right leg forward 20 degrees about the hip in the static posture
    R = cardan_xyz_to_matrix(np.array([0.0, -0.35, 0.0]))
    cal0 = calibrate(landmarks_to_markers(t), **SUBJECT)
    hjc = cal0.joint_centres_m["HJCr"]
    for name in ("GTr", "MRFr", "LEFr", "MEFr", "TTr", "LMr", "MMr", "CAr", "VMr", "FMr"):
        t[name] = hjc + R @ (t[name] - hjc)
    cal1 = calibrate(landmarks_to_markers(t), **SUBJECT)
    i = BODIES.index("thigh_r")
    np.testing.assert_allclose(cal1.body.inertia_kgm2[i], R @ cal0.body.inertia_kgm2[i] @ R.T, atol=1e-12)
    assert cal1.body.mass_kg[i] == cal0.body.mass_kg[i]


def test_missing_required_marker_names_it():
    with pytest.raises(InputError) as err:
        calibrate(_static(LEFr=None), **SUBJECT, source="static.c3d")
    assert "LEFr" in str(err.value) and "static.c3d" in str(err.value) and "knee" in str(err.value)
    with pytest.raises(InputError, match="PSISl"):
        calibrate(_static(PSISl=None), **SUBJECT)


def test_extra_tracking_markers_of_an_unknown_body_are_named():
    with pytest.raises(InputError, match=r"static\.c3d: extra_tracking_markers: got 'thigh' \(expected one of pelvis"):
        calibrate(_static(), **SUBJECT, extra_tracking_markers={"thigh": ("GTr",)}, source="static.c3d")


def test_lower_limb_marker_set_locks_the_hat():
    static = _static(C7=None, ST=None, ACr=None)
    with pytest.warns(GaitWarning, match="hat.*locked to pelvis"):
        cal = calibrate(static, **SUBJECT)
    assert cal.locked == ("hat",)
    assert cal.tracking_landmarks["hat"] == ()
    assert not cal.anatomical_from_landmarks[BODIES.index("hat")]
    assert any("locked" in n for n in cal.body.notes)


def test_virtual_joint_centres_are_used():
    t = standing_template(1.792, with_virtual_joint_centres=True)
    t["HJCr"] = t["HJCr"] + [0.01, 0.0, 0.0]
    t.pop("LEFl")  # not needed with KJCl
    cal = calibrate(landmarks_to_markers(t), **SUBJECT, hip_method="from_file")
    np.testing.assert_array_equal(cal.joint_centres_m["HJCr"], t["HJCr"])
    assert "KJCl" in cal.tracking_landmarks["thigh_l"] and "KJCl" in cal.tracking_landmarks["shank_l"]
    assert not cal.anatomical_from_landmarks[BODIES.index("thigh_l")]


def test_the_labs_hip_centres_are_ignored_unless_asked_for():
    t = standing_template(1.792, with_virtual_joint_centres=True)
    bell = jcm.hip_joint_centres(t["ASISr"], t["ASISl"], t["PSISr"], t["PSISl"])
    t["HJCr"] = t["HJCr"] + [0.01, 0.0, 0.0]
    cal = calibrate(landmarks_to_markers(t), **SUBJECT)  # the default: Bell (1990), as the dissertation
    np.testing.assert_allclose(cal.joint_centres_m["HJCr"], bell[0], atol=1e-15)
    assert "HJCr" not in cal.tracking_landmarks["pelvis"] and "HJCr" not in cal.tracking_landmarks["thigh_r"]
    t.pop("HJCl")
    with pytest.raises(InputError, match=r"static\.c3d: HJCl: hip_joint_centre is from_file"):
        calibrate(landmarks_to_markers(t), **SUBJECT, hip_method="from_file", source="static.c3d")


def test_disturbance_preset_moves_mass_and_keeps_joints():
    plain = calibrate(_static(), **SUBJECT)
    heavy = calibrate(_static(), **SUBJECT, disturbances=["ankle_weight"])
    i = BODIES.index("shank_r")
    assert heavy.body.mass_kg[i] - plain.body.mass_kg[i] == pytest.approx(1.719)
    assert heavy.com_m[i, 2] < plain.com_m[i, 2]  # the band pulls the CoM towards the ankle
    for j in range(7):  # joint centres stay where the static trial put them
        np.testing.assert_allclose(heavy.com_m[JOINT_PARENT[j]] + heavy.body.joint_in_parent_m[j],
                                   plain.com_m[JOINT_PARENT[j]] + plain.body.joint_in_parent_m[j], atol=1e-15)
        np.testing.assert_allclose(heavy.com_m[JOINT_CHILD[j]] + heavy.body.joint_in_child_m[j],
                                   plain.com_m[JOINT_CHILD[j]] + plain.body.joint_in_child_m[j], atol=1e-15)
    assert any("weight_band" in n for n in heavy.body.notes)


def test_static_landmarks_average_named_frames_ignoring_nan():
    rng = np.random.default_rng(5)
    pos = rng.normal(size=(10, 2, 3))
    pos[3, 0] = np.nan
    pos[:, 1] = np.nan
    m = Markers(("A", "B"), pos, 100.0)
    out = static_landmarks(m, frames=[1, 2, 3, 4])
    np.testing.assert_allclose(out["A"], pos[[1, 2, 4], 0].mean(0))
    assert "B" not in out


@pytest.mark.parametrize("heading_deg", [90.0, 180.0, 270.0, 21.0, -176.0])
def test_static_heading_changes_nothing_in_the_body(heading_deg):
    """A static facing any way calibrates the same body: parameters, clusters and anatomical offsets in body axes
    equal those of the static facing +x; positions are the static's own, turned. Plug-in Gait's static foot
    offsets (cgm.static_foot_offsets) do not turn with it either. (The whole idyn stage with a turned static:
    tests/dynamics/test_stage.py.)"""
    t = standing_template(1.792)
    turn = rot_z(np.radians(heading_deg))
    ahead = calibrate(landmarks_to_markers(t), **SUBJECT)
    turned = calibrate(landmarks_to_markers({k: turn @ v for k, v in t.items()}), **SUBJECT)
    for name in ("joint_in_parent_m", "joint_in_child_m", "inertia_kgm2", "mass_kg"):
        np.testing.assert_allclose(getattr(turned.body, name), getattr(ahead.body, name), atol=1e-12)
    np.testing.assert_allclose(turned.reference_to_anatomical, ahead.reference_to_anatomical, atol=1e-12)
    for b in BODIES:
        np.testing.assert_allclose(turned.cluster(b), ahead.cluster(b), atol=1e-12)
    np.testing.assert_allclose(turned.com_m, ahead.com_m @ turn.T, atol=1e-12)
    np.testing.assert_allclose(turned.static_rotation, turn @ ahead.static_rotation, atol=1e-12)
    assert any(f"faces {heading_deg:.1f}°" in n or f"faces {heading_deg - 360:.1f}°" in n for n in turned.notes)
    from gaitcli.kinematics import cgm

    pig = {k: t[k] for k in ("ASISr", "ASISl", "PSISr", "PSISl", "LEFr", "LEFl", "LMr", "LMl", "CAr", "CAl")}
    for s, lateral in (("r", -1.0), ("l", 1.0)):  # wands lateral and above the knee and ankle markers, the toe
        pig[f"THI{s}"] = t[f"LEF{s}"] + [0.02, 0.05 * lateral, 0.2]
        pig[f"TIB{s}"] = t[f"LM{s}"] + [0.01, 0.05 * lateral, 0.2]
        pig[f"MT2{s}"] = (t[f"FM{s}"] + t[f"VM{s}"]) / 2
    widths = {"r": 0.1, "l": 0.1}
    measurements = cgm.CgmMeasurements(leg_length_m={"r": 0.9, "l": 0.9}, knee_width_m=widths,
                                       ankle_width_m={"r": 0.07, "l": 0.07})
    offsets = [cgm.static_foot_offsets(P, measurements) for P in (pig, {k: turn @ v for k, v in pig.items()})]
    for name in ("plantarflexion_rad", "rotation_rad"):
        for s in "rl":
            assert getattr(offsets[1], name)[s] == pytest.approx(getattr(offsets[0], name)[s], abs=1e-12)


# ------------------------------------------------------------------ static_frames: auto

def _walk(flexion_r, flexion_l, pelvis_x):
    """Frames of the standing template with each knee flexed by the given angles (rad; shank and foot turned
    about the knee centre) and the whole body moved along x."""
    t = standing_template(1.78)
    frames = []
    for k in range(len(pelvis_x)):
        p = {}
        for name, pos in t.items():
            side = name[-1]
            theta = {"r": flexion_r, "l": flexion_l}.get(side, np.zeros(len(pelvis_x)))[k]
            if name[:-1] in ("TT", "LM", "MM", "CA", "VM", "FM"):
                knee = (t[f"LEF{side}"] + t[f"MEF{side}"]) / 2
                c, s = np.cos(theta), np.sin(theta)
                pos = knee + np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ (pos - knee)
            p[name] = pos + [pelvis_x[k], 0.0, 0.0]
        frames.append(p)
    return landmarks_to_markers({n: np.array([f[n] for f in frames]) for n in t})


def test_auto_static_frames_in_a_walk_are_the_frame_where_the_more_flexed_knee_is_straightest():
    n = 60
    rng = np.random.default_rng(4)
    flexion_r, flexion_l = rng.uniform(0.1, 1.0, n), rng.uniform(0.1, 1.0, n)
    flexion_r[17], flexion_l[17] = 0.02, 0.01  # the straightest …
    flexion_r[41], flexion_l[41] = 0.03, 0.04  # … and the next
    markers = _walk(flexion_r, flexion_l, np.arange(n) / 100.0)  # 1 m/s throughout: no standing
    frames, how = least_flexed_frames(markers)
    assert frames.tolist() == [17] and how.startswith("auto: no quiet standing")
    markers.positions_m[17, markers.index("FMr")] = np.nan  # a marker the calibration needs, not seen there
    assert least_flexed_frames(markers)[0].tolist() == [41]


def test_auto_static_frames_prefer_quiet_standing_with_straight_knees():
    x = np.concatenate([np.arange(100) / 100.0, np.full(150, 0.99)])  # walks 1 s, then stands 1.5 s
    flexion = np.full(250, 0.3)
    flexion[30] = 0.0  # a straight frame while walking does not count
    flexion[100:150], flexion[150:] = 0.15, 0.05
    frames, how = least_flexed_frames(_walk(flexion, flexion, x))
    assert frames.tolist() == list(range(150, 250))  # 1 s, the straightest stretch of the standing
    # 0.05 rad = 2.9°, plus the template's 0.6°: its mid-malleoli sit 4.5 mm behind the knee–hip line
    assert how.startswith("auto: 100 frames of quiet standing") and "3.4°" in how


@pytest.mark.shared
def test_auto_static_frames_on_qualisys_pick_the_frame_the_worked_example_chose(shared_c3d_dir):
    import yaml

    from gaitcli.io.c3d import read_c3d
    from gaitcli.signal.stage import FilterConfig, filter_markers, with_session_defaults

    subject = yaml.safe_load((Path(__file__).resolve().parents[2] / "docs" / "examples" / "qualisys"
                              / "subject.yaml").read_text())
    markers, _ = filter_markers(marker_set("cast").apply(read_c3d(shared_c3d_dir / "Qualisys.c3d").markers),
                                with_session_defaults(FilterConfig(), "cast"))  # as the idyn stage sees them
    frames, _ = least_flexed_frames(markers)
    assert [int(frames[0]) + markers.first_frame] * 2 == subject["static_frames"]  # chosen by hand: [992, 992]


def test_plug_in_gaits_foot_runs_from_the_ankle_centre_to_the_toe():
    """``segment_inertias="plug_in_gait"``: each foot's CoM halfway between the ankle centre and the toe marker
    (MT2), no inertia about that line and m (0.69 L)² about every line across it (L = ankle centre to toe); the
    thigh's CoM 43.3 % of the way from hip to knee centre; the body's joints where de Leva's body has them."""
    t = standing_template(1.792)
    for s in "rl":
        t[f"MT2{s}"] = (t[f"FM{s}"] + t[f"VM{s}"]) / 2 + [0.0, 0.0, 0.01]
    pig = calibrate(landmarks_to_markers(t), **SUBJECT, segment_inertias="plug_in_gait")
    plain = calibrate(landmarks_to_markers(t), **SUBJECT)
    c = pig.joint_centres_m
    for s in "rl":
        foot = BODIES.index(f"foot_{s}")
        toe = pig.static_landmarks_m[f"MT2{s}"]
        np.testing.assert_allclose(pig.com_m[foot], (c[f"AJC{s}"] + toe) / 2, atol=1e-15)
        along = (toe - c[f"AJC{s}"]) / np.linalg.norm(toe - c[f"AJC{s}"])
        inertia, m, length = pig.body.inertia_kgm2[foot], pig.body.mass_kg[foot], np.linalg.norm(toe - c[f"AJC{s}"])
        assert along @ inertia @ along == pytest.approx(0.0, abs=1e-15)
        across = np.cross(along, [0.0, 0.0, 1.0])
        across /= np.linalg.norm(across)
        assert across @ inertia @ across == pytest.approx(m * (0.69 * length) ** 2)
        thigh = BODIES.index(f"thigh_{s}")
        np.testing.assert_allclose(pig.com_m[thigh], c[f"HJC{s}"] + 0.433 * (c[f"KJC{s}"] - c[f"HJC{s}"]),
                                   atol=1e-15)
    for name in c:
        np.testing.assert_allclose(c[name], plain.joint_centres_m[name], atol=1e-15)
    assert pig.body.total_mass_kg == pytest.approx(73.0, abs=1e-12)
    assert any("the legs Plug-in Gait's" in n for n in pig.notes)
    with pytest.raises(InputError, match="segment_inertias"):
        calibrate(landmarks_to_markers(t), **SUBJECT, segment_inertias="dempster")
