"""Plug-in Gait's frames and angles (kinematics/cgm.py, kinematics/anatomical.py).

Known answers: a leg built from chosen joint angles, its markers placed where the Conventional Gait Model puts
them (the lateral markers one chord offset from the joint centres, the wands in the frontal planes), gives those
angles back; and on a real Vicon session the angles from the file's markers equal the ones Vicon Nexus stored in
the same file (its static foot offsets too)."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.kinematics import cgm
from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES, PIG_FOOT_AXES, anatomical_angles
from gaitcli.kinematics.rotations import rot_x, rot_y, rot_z

MEASUREMENTS = cgm.CgmMeasurements(leg_length_m={"r": 0.90, "l": 0.90}, knee_width_m={"r": 0.10, "l": 0.10},
                                   ankle_width_m={"r": 0.07, "l": 0.07}, marker_diameter_m=0.014)


def _leg_markers(angles_deg: dict, pelvis: np.ndarray, origin: np.ndarray) -> dict:
    """Markers of a pelvis at ``origin`` with axes ``pelvis`` and both legs at the given clinical angles (deg):
    ``{side: (hip flex, add, rot, knee flex, add, rot, ankle dorsiflexion, ankle rotation)}``."""
    P = {"ASISr": origin - 0.12 * pelvis[:, 1], "ASISl": origin + 0.12 * pelvis[:, 1]}
    P["PSISr"] = P["PSISl"] = origin - 0.16 * pelvis[:, 0]
    hips = cgm.davis_hip_joint_centres(P["ASISr"], P["ASISl"], P["PSISr"], P["PSISl"], leg_length_m=0.90,
                                       marker_radius_m=0.007)
    r = MEASUREMENTS.marker_radius_m
    for side, hip in zip("rl", hips):
        s = 1.0 if side == "r" else -1.0
        hf, ha, hr, kf, ka, kr, dorsi, ar = np.radians(angles_deg[side])
        thigh = pelvis @ rot_y(-hf) @ rot_x(s * ha) @ rot_z(s * hr)
        knee = hip - 0.42 * thigh[:, 2]
        shank = thigh @ rot_y(kf) @ rot_x(s * ka) @ rot_z(s * kr)
        ankle = knee - 0.40 * shank[:, 2]
        foot = shank @ rot_y(-dorsi - np.pi / 2) @ rot_x(s * ar)  # Plug-in Gait's axes: z from toe to heel
        lateral = -s  # the lateral side is −y on the right
        P[f"LEF{side}"] = knee + lateral * (MEASUREMENTS.knee_width_m[side] / 2 + r) * thigh[:, 1]
        P[f"THI{side}"] = knee + 0.2 * thigh[:, 2] + lateral * 0.12 * thigh[:, 1]
        P[f"LM{side}"] = ankle + lateral * (MEASUREMENTS.ankle_width_m[side] / 2 + r) * shank[:, 1]
        P[f"TIB{side}"] = ankle + 0.2 * shank[:, 2] + lateral * 0.10 * shank[:, 1]
        P[f"MT2{side}"] = ankle - 0.15 * foot[:, 2]
        P[f"CA{side}"] = ankle + 0.05 * foot[:, 2]  # on the ankle–toe line: the static offsets are zero
    return P


ANGLES = {"r": (25.0, 4.0, -7.0, 40.0, 2.0, 5.0, 8.0, -6.0), "l": (-10.0, -3.0, 9.0, 12.0, -1.5, -4.0, -12.0, 10.0)}


@pytest.mark.parametrize("heading_deg", [0.0, 90.0, 21.0])
def test_a_leg_built_from_angles_gives_them_back(heading_deg):
    """Hip, knee and ankle angles of an exact synthetic pelvis–thigh–shank–foot chain; the pelvis tilted, raised
    and turned; the pelvis angles are its Cardan angles against the progression frame (x along the walk)."""
    tilt, obliquity, rotation = 12.0, 3.0, 5.0
    in_progression = rot_y(np.radians(tilt)) @ rot_x(np.radians(-obliquity)) @ rot_z(np.radians(rotation))
    P = _leg_markers(ANGLES, rot_z(np.radians(heading_deg)) @ in_progression, np.array([0.3, 0.1, 0.95]))
    frames = cgm.leg_frames(P, MEASUREMENTS)
    offsets = cgm.static_foot_offsets(P, MEASUREMENTS)
    assert max(abs(v) for d in (offsets.plantarflexion_rad, offsets.rotation_rad) for v in d.values()) < 1e-12
    got = np.degrees(anatomical_angles(cgm.anatomical_frames(frames, offsets), ankle="plug_in_gait"))
    for side, values in ANGLES.items():
        expected = dict(zip(("hip_{s}_flexion", "hip_{s}_adduction", "hip_{s}_rotation", "knee_{s}_flexion",
                             "knee_{s}_adduction", "knee_{s}_rotation", "ankle_{s}_flexion", "ankle_{s}_rotation"),
                            values))
        for name, value in expected.items():
            assert got[ANATOMICAL_ANGLES.index(name.format(s=side))] == pytest.approx(value, abs=1e-9), name
        assert got[ANATOMICAL_ANGLES.index(f"ankle_{side}_inversion")] == pytest.approx(0.0, abs=1e-9)
    if heading_deg == 0.0:  # walking along x: the pelvis's Cardan angles against the model axes
        assert got[:3] == pytest.approx((tilt, obliquity, rotation), abs=1e-9)


def test_a_body_turned_about_the_vertical_keeps_its_joint_angles():
    """Turning everything by 15° about the vertical: a level pelvis's rotation + 15°, every joint angle the same."""
    P = _leg_markers(ANGLES, np.eye(3), np.array([0.0, 0.0, 0.95]))
    turned = {k: rot_z(np.radians(15.0)) @ v for k, v in P.items()}
    a, b = (np.degrees(anatomical_angles(cgm.anatomical_frames(cgm.leg_frames(Q, MEASUREMENTS),
                                                               cgm.static_foot_offsets(Q, MEASUREMENTS)),
                                         ankle="plug_in_gait")) for Q in (P, turned))
    diff = dict(zip(ANATOMICAL_ANGLES, b - a))
    assert diff.pop("pelvis_rotation") == pytest.approx(15.0, abs=1e-9)
    joints = [v for k, v in diff.items() if not k.startswith(("pelvis", "foot"))]
    assert np.max(np.abs(joints)) < 1e-9


def _frames(**feet):
    level = np.eye(3)
    return {"pelvis": level, **{f"{b}_{s}": level for b in ("thigh", "shank") for s in "rl"},
            "foot_r": feet.get("foot_r", level), "foot_l": feet.get("foot_l", level)}


def test_a_level_foot_turned_inwards_progresses_inwards_on_both_sides():
    """A flat foot whose toes point 12° towards the other foot: foot progression +12° on either side."""
    inward = np.radians(12.0)
    got = np.degrees(anatomical_angles(_frames(foot_r=rot_z(inward), foot_l=rot_z(-inward)), ankle="plug_in_gait"))
    assert got[ANATOMICAL_ANGLES.index("foot_r_progression")] == pytest.approx(12.0, abs=1e-9)
    assert got[ANATOMICAL_ANGLES.index("foot_l_progression")] == pytest.approx(12.0, abs=1e-9)


@pytest.mark.parametrize("ankle", ["plug_in_gait", "isb"])
def test_each_ankle_convention_decomposes_its_own_sequence(ankle):
    """Dorsiflexion 20°, rotation 10° (toes in), inversion 8° (sole turned in) composed in each convention's own
    Cardan order come back exactly; Plug-in Gait's foot axes turn about its long axis (toe → heel) last."""
    d, rot, inv = np.radians([20.0, 10.0, 8.0])
    if ankle == "isb":
        foot = rot_y(-d) @ rot_x(inv) @ rot_z(rot)
    else:
        foot = rot_y(-d - np.pi / 2) @ rot_x(rot) @ rot_z(-inv) @ PIG_FOOT_AXES.T
    got = np.degrees(anatomical_angles(_frames(foot_r=foot), ankle=ankle))
    k = ANATOMICAL_ANGLES.index
    assert (got[k("ankle_r_flexion")], got[k("ankle_r_rotation")], got[k("ankle_r_inversion")]) == \
        pytest.approx((20.0, 10.0, 8.0), abs=1e-9)


def test_pig_foot_axes_are_a_rotation():
    assert np.allclose(PIG_FOOT_AXES @ PIG_FOOT_AXES.T, np.eye(3)) and np.linalg.det(PIG_FOOT_AXES) == 1.0


# ------------------------------------------------------------------ a real Vicon session

MAP = {"ASIS": "ASI", "PSIS": "PSI", "LEF": "KNE", "LM": "ANK", "MT2": "TOE", "CA": "HEE", "THI": "THI",
       "TIB": "TIB"}


def _vicon(path):
    import ezc3d

    c3d = ezc3d.c3d(str(path))
    labels = c3d["parameters"]["POINT"]["LABELS"]["value"]
    points = c3d["data"]["points"][:3].transpose(2, 1, 0)
    metadata = {f"PROCESSING:{k}": float(np.ravel(v["value"])[0]) for k, v in c3d["parameters"]["PROCESSING"].items()
                if isinstance(v, dict) and np.size(v.get("value", [])) and not isinstance(v["value"][0], str)}
    return labels, points, metadata


def _landmarks(labels, points, *, mean=False):
    out = {}
    for landmark, label in MAP.items():
        for s, S in (("r", "R"), ("l", "L")):
            p = points[:, labels.index(S + label)] / 1000.0
            out[landmark + s] = p.mean(axis=0) if mean else p
    return out


def test_vicon_plug_in_gait_angles_and_static_offsets_are_reproduced(shared_pig_dir):
    """Vicon's RHipAngles … LFootProgressAngles from the file's own markers (progression along lab −x) to 0.01°,
    and the static foot offsets Nexus wrote into PROCESSING to 5e-5 rad (it averages per-frame offsets, we the
    markers) (its signs: plantarflexion positive, the left rotation mirrored)."""
    s_labels, s_points, _ = _vicon(shared_pig_dir / "Static_trial.c3d")
    labels, points, metadata = _vicon(shared_pig_dir / "Movement_trial.c3d")
    m = cgm.measurements_from(metadata)
    assert m is not None and m.inter_asis_m == pytest.approx(0.306)
    offsets = cgm.static_foot_offsets(_landmarks(s_labels, s_points, mean=True), m)
    for s, S, mirror in (("r", "R", 1.0), ("l", "L", -1.0)):
        assert -offsets.plantarflexion_rad[s] == pytest.approx(metadata[f"PROCESSING:{S}StaticPlantFlex"], abs=5e-5)
        assert mirror * offsets.rotation_rad[s] == pytest.approx(metadata[f"PROCESSING:{S}StaticRotOff"], abs=5e-5)
    lab_to_progression = np.diag([-1.0, -1.0, 1.0])
    frames = {b: lab_to_progression @ R
              for b, R in cgm.anatomical_frames(cgm.leg_frames(_landmarks(labels, points), m), offsets).items()}
    ours = np.degrees(anatomical_angles(frames, ankle="plug_in_gait"))
    names = {"pelvis": "PelvisAngles", "hip": "HipAngles", "knee": "KneeAngles", "ankle": "AnkleAngles",
             "foot": "FootProgressAngles"}
    for k, column in enumerate(ANATOMICAL_ANGLES):
        part = column.split("_")
        side = "R" if column.startswith("pelvis") or part[1] == "r" else "L"
        component = {"flexion": 0, "tilt": 0, "adduction": 1, "inversion": 1, "obliquity": 1, "rotation": 2,
                     "progression": 2}[part[-1]]
        sign = -1.0 if part[-1] == "inversion" else 1.0  # Vicon's AnkleAngles Y turns about the toe → heel axis
        vicon = sign * points[:, labels.index(side + names[part[0]]), component]
        assert np.max(np.abs(ours[:, k] - vicon)) < 0.01, column


def test_the_hub_of_a_knee_alignment_device_is_the_corner_of_its_arms():
    """Three mutually orthogonal arms of 80 mm from a hub at the right knee marker, KAX along the knee axis
    (laterally, −y), KD1 and KD2 in the sagittal plane: the hub comes back from the three markers alone,
    whichever of KD1 and KD2 is which, turned and moved anywhere."""
    hub = np.array([0.02, -0.11, 0.48])
    lateral = np.array([0.0, -1.0, 0.0])
    b = np.array([np.cos(0.6), 0.0, np.sin(0.6)])
    c = np.cross(lateral, b)
    for R in (np.eye(3), rot_z(2.5) @ rot_x(0.3)):
        kax, kd1, kd2 = (R @ (hub + 0.08 * d) for d in (lateral, b, c))
        np.testing.assert_allclose(cgm.kad_hub(kax, kd1, kd2, R @ lateral), R @ hub, atol=1e-12)
        np.testing.assert_allclose(cgm.kad_hub(kax, kd2, kd1, R @ lateral), R @ hub, atol=1e-12)
