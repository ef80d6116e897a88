"""Joint centres (Bell, epicondyles, malleoli) and anatomical frames on synthetic geometry."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.kinematics import joint_centres as jcm
from gaitcli.kinematics.markerset import standing_template
from gaitcli.kinematics.rotations import cardan_xyz_to_matrix

RNG = np.random.default_rng(11)
PW = 0.24


def _random_poses(n):
    return cardan_xyz_to_matrix(RNG.uniform(-np.pi, np.pi, (n, 3))), RNG.normal(size=(n, 3))


def _place(R, t, p):
    return np.einsum("nij,j->ni", R, p) + t


def test_bell_1990_on_a_rotated_pelvis_of_known_geometry():
    # pelvis frame = identity: ASIS on the y axis, PSIS behind them in the same horizontal plane
    asis_r, asis_l = np.array([0, -PW / 2, 0]), np.array([0, PW / 2, 0])
    psis_r, psis_l = np.array([-0.16, -0.04, 0]), np.array([-0.16, 0.04, 0])
    expected_r = PW * np.array([-0.19, -0.36, -0.30])
    expected_l = PW * np.array([-0.19, 0.36, -0.30])
    R, t = _random_poses(50)
    hjc_r, hjc_l = jcm.hip_joint_centres(*(_place(R, t, p) for p in (asis_r, asis_l, psis_r, psis_l)))
    np.testing.assert_allclose(hjc_r, _place(R, t, expected_r), atol=1e-14)
    np.testing.assert_allclose(hjc_l, _place(R, t, expected_l), atol=1e-14)
    # Bell 1989 (from each ASIS: 22 % posterior, 30 % distal, 14 % medial): same except 3 % PW further back
    old_r, _ = jcm.hip_joint_centres(*(_place(R, t, p) for p in (asis_r, asis_l, psis_r, psis_l)), method="bell1989")
    np.testing.assert_allclose(old_r, _place(R, t, expected_r + [-0.03 * PW, 0, 0]), atol=1e-14)


def test_pelvis_frame_follows_the_asis_psis_plane():
    depth, rise = 0.16, 0.05  # PSIS higher than ASIS: the frame tilts about y
    asis_r, asis_l = np.array([0, -PW / 2, 0.0]), np.array([0, PW / 2, 0.0])
    psis = [np.array([-depth, s * 0.04, rise]) for s in (-1, 1)]
    origin, R = jcm.pelvis_frame(asis_r, asis_l, *psis)
    norm = np.hypot(depth, rise)
    np.testing.assert_allclose(R[:, 0], [depth / norm, 0, -rise / norm], atol=1e-15)
    np.testing.assert_allclose(R[:, 2], [rise / norm, 0, depth / norm], atol=1e-15)
    hjc_r, _ = jcm.hip_joint_centres(asis_r, asis_l, *psis)
    np.testing.assert_allclose(hjc_r, origin + PW * (-0.19 * R[:, 0] - 0.36 * R[:, 1] - 0.30 * R[:, 2]))


def test_knee_and_ankle_centres():
    lef, mef = np.array([0.01, -0.15, 0.5]), np.array([0.0, -0.05, 0.5])
    np.testing.assert_allclose(jcm.knee_joint_centre(lef, mef), [0.005, -0.1, 0.5])
    kjc = np.array([0.0, -0.1, 0.5])
    lm, mm = np.array([-0.01, -0.14, 0.07]), np.array([0.01, -0.06, 0.08])
    mid = (lm + mm) / 2
    np.testing.assert_allclose(jcm.ankle_joint_centre(lm, mm, method="midpoint"), mid)
    ajc = jcm.ankle_joint_centre(lm, mm, kjc, sex="male")
    # on the knee -> mid-malleoli line, longer by de Leva's 440.3/434.0
    assert np.linalg.norm(ajc - kjc) == pytest.approx(np.linalg.norm(mid - kjc) * 440.3 / 434.0)
    np.testing.assert_allclose(np.cross(ajc - kjc, mid - kjc), 0.0, atol=1e-15)


def test_virtual_centres_replace_estimates_and_missing_markers_are_named():
    t = standing_template(1.75)
    virtual = t["HJCr"] = t["HJCl"] = np.array([0.01, 0.0, 0.9])
    t["KJCl"] = np.array([0.0, 0.1, 0.5])
    out = jcm.joint_centres(t)
    np.testing.assert_array_equal(out["HJCr"], virtual)
    np.testing.assert_array_equal(out["KJCl"], t["KJCl"])
    np.testing.assert_allclose(out["KJCr"], (t["LEFr"] + t["MEFr"]) / 2)
    del t["MMr"]
    with pytest.raises(InputError, match="MMr.*ankle"):
        jcm.joint_centres(t, source="static.c3d")


def test_unknown_methods_are_input_errors():
    t = standing_template(1.75)
    with pytest.raises(InputError, match=r"hip_method: got 'bell90' \(expected one of bell1990, bell1989; "
                                         r"did you mean 'bell1990'\?\)"):
        jcm.joint_centres(t, hip_method="bell90")
    with pytest.raises(InputError, match=r"ankle_method: got 'midpt' .*did you mean 'midpoint'\?"):
        jcm.joint_centres(t, ankle_method="midpt")


def test_anatomical_frames_are_rotations_and_identity_in_the_template():
    t = standing_template(1.8, with_virtual_joint_centres=True)
    frames = {
        "thigh_r": jcm.thigh_frame(t["HJCr"], t["KJCr"], t["LEFr"], t["MEFr"], side="r"),
        "thigh_l": jcm.thigh_frame(t["HJCl"], t["KJCl"], t["LEFl"], t["MEFl"], side="l"),
        "shank_l": jcm.shank_frame(t["KJCl"], t["AJCl"], t["LMl"], t["MMl"], side="l"),
        "pelvis": jcm.pelvis_frame(t["ASISr"], t["ASISl"], t["PSISr"], t["PSISl"])[1],
    }
    for name, R in frames.items():
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14, err_msg=name)
        assert np.linalg.det(R) == pytest.approx(1.0)
        if name != "shank_l":  # the template stands upright; its malleolar axis is externally rotated
            np.testing.assert_allclose(R, np.eye(3), atol=1e-12, err_msg=name)
    shank = frames["shank_l"]
    np.testing.assert_allclose(shank[:, 2], [0.0, 0.0, 1.0], atol=0.011)  # long axis still nearly vertical
    foot = jcm.foot_frame(t["CAr"], t["VMr"], t["FMr"], side="r")
    assert foot[0, 0] > 0.99 and foot[2, 2] > 0.97  # x forward along the foot, z up
    fallback = jcm.thigh_frame(t["HJCr"], t["KJCr"], side="r")
    np.testing.assert_allclose(fallback, np.eye(3), atol=1e-12)


@pytest.mark.parametrize("primary, secondary", [("x", "y"), ("y", "x"), ("z", "y"), ("x", "z"), ("z", "x"), ("y", "z")])
def test_frame_from_axes_is_right_handed(primary, secondary):
    a, b = RNG.normal(size=(20, 3)), RNG.normal(size=(20, 3))
    R = jcm.frame_from_axes(a, b, primary_axis=primary, secondary_axis=secondary)
    np.testing.assert_allclose(np.linalg.det(R), 1.0)
    i = "xyz".index(primary)
    np.testing.assert_allclose(R[..., i], a / np.linalg.norm(a, axis=-1, keepdims=True))


# ------------------------------------------------------------------ Harrington (2007) and Hara (2016)

_PELVIS = {"ASISr": np.array([0.0, -0.125, 1.0]), "ASISl": np.array([0.0, 0.125, 1.0]),
           "PSISr": np.array([-0.18, -0.05, 1.0]), "PSISl": np.array([-0.18, 0.05, 1.0])}  # PW 0.25, PD 0.18 m


@pytest.mark.parametrize("method,right", [
    # by hand, mm: Harrington x = −9.9 − 0.24·180 = −53.1, superior −7.1 − 0.16·250 − 0.04·900 = −83.1,
    # lateral 7.9 + 0.28·180 + 0.16·250 = 98.3; Hara x = 11 − 0.063·900 = −45.7, superior −9 − 0.078·900 =
    # −79.2, lateral 8 + 0.086·900 = 85.4
    ("harrington", (-0.0531, -0.0983, 1.0 - 0.0831)),
    ("hara", (-0.0457, -0.0854, 1.0 - 0.0792)),
])
def test_regression_hip_centres_equal_the_published_equations(method, right):
    hjc_r, hjc_l = jcm.regression_hip_joint_centres(*(_PELVIS[n] for n in ("ASISr", "ASISl", "PSISr", "PSISl")),
                                                    method=method, leg_length_m=0.9)
    np.testing.assert_allclose(hjc_r, right, atol=1e-12)
    np.testing.assert_allclose(hjc_l, np.array(right) * [1, -1, 1], atol=1e-12)
    # the same pelvis turned 90° about the vertical and tilted 10° forward: the centres turn with it
    turn = cardan_xyz_to_matrix(np.array([0.0, np.radians(10.0), np.radians(90.0)]))
    moved = [turn @ _PELVIS[n] + [1.0, 2.0, 0.0] for n in ("ASISr", "ASISl", "PSISr", "PSISl")]
    got = jcm.regression_hip_joint_centres(*moved, method=method, leg_length_m=0.9)
    np.testing.assert_allclose(got[0], turn @ np.array(right) + [1.0, 2.0, 0.0], atol=1e-12)


def test_the_regressions_take_the_leg_length_from_the_malleoli_or_subject_yaml():
    t = standing_template(1.8)
    length = np.mean([np.linalg.norm(t[f"ASIS{s}"] - t[f"MM{s}"]) for s in "rl"])
    pelvis = [t[n] for n in ("ASISr", "ASISl", "PSISr", "PSISl")]
    out = jcm.joint_centres(t, hip_method="hara")
    np.testing.assert_allclose(out["HJCr"], jcm.regression_hip_joint_centres(*pelvis, method="hara",
                                                                               leg_length_m=length)[0])
    given = jcm.joint_centres(t, hip_method="hara", leg_length=0.95)
    np.testing.assert_allclose(given["HJCr"], jcm.regression_hip_joint_centres(*pelvis, method="hara",
                                                                                 leg_length_m=0.95)[0])
    del t["MMr"], t["MMl"]
    t["AJCr"], t["AJCl"] = t["LMr"], t["LMl"]
    lateral = np.mean([np.linalg.norm(t[f"ASIS{s}"] - t[f"LM{s}"]) for s in "rl"])  # Plug-in Gait: no medial marker
    np.testing.assert_allclose(jcm.joint_centres(t, hip_method="hara")["HJCr"],
                               jcm.regression_hip_joint_centres(*pelvis, method="hara", leg_length_m=lateral)[0])
    del t["LMr"], t["LMl"]
    with pytest.raises(InputError, match="leg_length_m"):
        jcm.joint_centres(t, hip_method="harrington", source="static.c3d")


# ------------------------------------------------------------------ SCORE (Ehrig et al. 2006)

def _poses_about(point_parent, point_child, angles):
    """Parent and child poses (n frames) with the child turned by ``angles`` (n, 3) Cardan x-y-z about a point
    at ``point_parent`` in the parent and ``point_child`` in the child; the parent moves and turns too."""
    n = len(angles)
    R_p = np.array([cardan_xyz_to_matrix(np.array([0.1 * np.sin(k), 0.05 * k / n, 0.2])) for k in range(n)])
    d_p = np.column_stack([np.linspace(0, 1.5, n), 0.02 * np.sin(np.arange(n)), np.full(n, 0.9)])
    R_c = R_p @ np.array([cardan_xyz_to_matrix(a) for a in angles])
    joint = d_p + np.einsum("nij,j->ni", R_p, point_parent)
    d_c = joint - np.einsum("nij,j->ni", R_c, point_child)
    return R_p, d_p, R_c, d_c


def test_score_finds_the_point_fixed_in_both_bodies():
    rng = np.random.default_rng(3)
    c_p, c_c = np.array([-0.02, -0.09, -0.08]), np.array([0.01, 0.0, 0.2])
    angles = rng.uniform(-0.5, 0.5, (60, 3))  # a star arc: all three axes
    got_p, got_c, rms, spread = jcm.functional_joint_centre(*_poses_about(c_p, c_c, angles))
    np.testing.assert_allclose(got_p, c_p, atol=1e-12)
    np.testing.assert_allclose(got_c, c_c, atol=1e-12)
    assert rms < 1e-12 and spread < 1e-10
    R_p, d_p, R_c, d_c = _poses_about(c_p, c_c, angles)
    d_c += rng.normal(0, 0.002, d_c.shape)  # 2 mm per axis on the child's position: 3.5 mm in 3-D
    got_p, _, rms, spread = jcm.functional_joint_centre(R_p, d_p, R_c, d_c)
    assert 2e-3 < rms < 5e-3 and np.linalg.norm(got_p - c_p) < spread < 0.03


def test_score_says_when_one_axis_of_motion_leaves_the_centre_undetermined():
    angles = np.zeros((60, 3))
    angles[:, 1] = np.linspace(-0.5, 0.5, 60)  # flexion only: the centre may slide along the flexion axis
    R_p, d_p, R_c, d_c = _poses_about(np.array([0.0, -0.09, -0.08]), np.array([0.0, 0.0, 0.2]), angles)
    d_c += np.random.default_rng(5).normal(0, 0.001, d_c.shape)
    _, _, rms, spread = jcm.functional_joint_centre(R_p, d_p, R_c, d_c)
    assert rms < 2e-3 and spread > 0.1


# ------------------------------------------------------------------ Davis (1991) and the chord method (Plug-in Gait)

def test_davis_hip_centres_equal_the_hand_evaluated_equations():
    """Leg length 900 mm, marker radius 7 mm, inter-ASIS 250 mm: C = 0.115·900 − 15.3 = 88.2 mm, X_dis =
    0.1288·900 − 48.56 = 67.36 mm; with θ = 0.5, β = 0.314 rad: x = 88.2·cos θ·sin β − 74.36·cos β = −46.817 mm,
    lateral 125 − 88.2·sin θ = 82.715 mm, z = −88.2·cos θ·cos β − 74.36·sin β = −96.585 mm (pelvis frame)."""
    asis_r, asis_l = np.array([0.0, -0.125, 0.0]), np.array([0.0, 0.125, 0.0])
    psis_r, psis_l = np.array([-0.16, -0.04, 0.0]), np.array([-0.16, 0.04, 0.0])
    right, left = jcm.davis_hip_joint_centres(asis_r, asis_l, psis_r, psis_l, leg_length_m=0.9, marker_radius_m=0.007)
    np.testing.assert_allclose(right, [-0.046817, -0.082715, -0.096585], atol=1e-6)
    np.testing.assert_allclose(left, [-0.046817, 0.082715, -0.096585], atol=1e-6)
    R, t = _random_poses(1)
    moved = [R[0] @ p + t[0] for p in (asis_r, asis_l, psis_r, psis_l)]
    got = jcm.davis_hip_joint_centres(*moved, leg_length_m=0.9, marker_radius_m=0.007)
    np.testing.assert_allclose(got[0], R[0] @ right + t[0], atol=1e-12)
    landmarks = dict(zip(("ASISr", "ASISl", "PSISr", "PSISl"), (asis_r, asis_l, psis_r, psis_l)))
    landmarks.update({f"{n}{s}": np.zeros(3) for n in ("LEF", "MEF", "LM", "MM") for s in "rl"})
    out = jcm.joint_centres(landmarks, hip_method="davis", leg_length=0.9,
                            widths=jcm.JointWidths(marker_diameter_m=0.014))
    np.testing.assert_allclose(out["HJCr"], right, atol=1e-12)


def _chord_knee(R, t, delta=0.05, side=-1.0):
    """A right knee: hip centre 0.4 m above the knee centre, the knee marker ``delta`` lateral of it, the wand
    lateral of the mid-thigh (in the frontal plane), all turned by ``R`` and moved by ``t``."""
    hjc, kjc = np.array([0.0, 0.0, 0.9]), np.array([0.0, 0.0, 0.5])
    kne, thi = kjc + [0.0, side * delta, 0.0], np.array([0.0, side * 0.09, 0.7])
    return [R @ p + t for p in (hjc, thi, kne, kjc)]


def test_the_chord_method_recovers_a_knee_centre_of_known_geometry():
    for R, t in zip(*_random_poses(5)):
        hjc, thi, kne, kjc = _chord_knee(R, t)
        np.testing.assert_allclose(jcm.chord_joint_centre(hjc, thi, kne, 0.05), kjc, atol=1e-12)
    stacked = [np.stack(p) for p in zip(*(_chord_knee(R, t) for R, t in zip(*_random_poses(4))))]
    np.testing.assert_allclose(jcm.chord_joint_centre(*stacked[:3], np.full(4, 0.05)), stacked[3], atol=1e-12)
    # the defining properties, for an off-plane wand too: |J − KNE| = δ and (HJC − J) ⊥ (KNE − J)
    hjc, kne, wand = np.array([0.1, 0.2, 0.9]), np.array([0.13, 0.11, 0.48]), np.array([0.2, 0.05, 0.7])
    j = jcm.chord_joint_centre(hjc, wand, kne, 0.055)
    assert abs(np.linalg.norm(j - kne) - 0.055) < 1e-12 and abs(np.dot(hjc - j, kne - j)) < 1e-12


def test_a_chord_turned_by_a_rotation_offset_finds_the_centre_of_a_wand_placed_off_its_plane():
    """A thigh wand placed 25° around the thigh from the knee axis's plane (about the knee marker → hip line):
    the plain chord misses the knee centre by the chord of a 25° arc of the circle it turns on, radius
    δ √(1 − δ²/L²) (L the knee marker–hip distance): 21.5 mm; the chord turned back by −25° (Plug-in Gait's
    thigh rotation offset) finds it."""
    hjc, thi, kne, kjc = _chord_knee(np.eye(3), np.zeros(3))
    u = (hjc - kne) / np.linalg.norm(hjc - kne)
    a = np.radians(25.0)
    v = thi - kne
    turned = kne + v * np.cos(a) + np.cross(u, v) * np.sin(a) + u * np.dot(u, v) * (1 - np.cos(a))
    missed = jcm.chord_joint_centre(hjc, turned, kne, 0.05)
    radius = 0.05 * np.sqrt(1 - (0.05 / np.linalg.norm(hjc - kne)) ** 2)
    assert np.linalg.norm(missed - kjc) == pytest.approx(2 * radius * np.sin(a / 2), rel=1e-9)
    np.testing.assert_allclose(jcm.chord_joint_centre(hjc, turned, kne, 0.05, -a), kjc, atol=1e-12)


def test_knee_and_ankle_centres_by_the_chord_method_need_width_and_wand():
    t = standing_template(1.8, with_virtual_joint_centres=True)
    truth = {k: t.pop(k) for k in ("HJCr", "HJCl", "KJCr", "KJCl", "AJCr", "AJCl")}
    t["HJCr"], t["HJCl"] = truth["HJCr"], truth["HJCl"]
    for s, lateral in (("r", -1.0), ("l", 1.0)):
        del t[f"MEF{s}"], t[f"MM{s}"]
        t[f"{s.upper()}THI"] = (truth[f"HJC{s}"] + truth[f"KJC{s}"]) / 2 + [0.0, 0.08 * lateral, 0.0]
        t[f"{s.upper()}TIB"] = (truth[f"KJC{s}"] + truth[f"AJC{s}"]) / 2 + [0.0, 0.07 * lateral, 0.0]
        t[f"LM{s}"] = truth[f"AJC{s}"] + [0.0, 0.035 * lateral, 0.0]
    knee = float(np.linalg.norm(t["LEFr"] - truth["KJCr"]))
    widths = jcm.JointWidths(knee_m={"r": 2 * knee - 0.014, "l": 2 * knee - 0.014},
                             ankle_m={"r": 0.07 - 0.014, "l": 0.07 - 0.014}, marker_diameter_m=0.014,
                             wands={"thigh_r": ("RTHI",), "thigh_l": ("LTHI",), "shank_r": ("RTIB",),
                                    "shank_l": ("LTIB",)})
    out = jcm.joint_centres(t, widths=widths)
    for name in ("KJCr", "KJCl", "AJCr", "AJCl"):
        np.testing.assert_allclose(out[name], truth[name], atol=1e-12)
    with pytest.raises(InputError, match="MEFr"):  # no width: the medial marker is needed after all
        jcm.joint_centres(t, widths=jcm.JointWidths(wands=widths.wands))
