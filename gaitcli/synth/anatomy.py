"""The synthetic body's anatomy: its true anatomical frames and anatomical joint angles (the truth of ``gait synth``).

What "true" means here. The synthetic body is rigid segments with known joint centres (``HJC``, ``KJC``, ``AJC``:
the body's own, :attr:`SyntheticTrial.calibration`), joint axes and landmarks standing where the template puts
them. An anatomical frame is a definition on anatomy — which points and axes span it — so the true frame is that
definition applied to the body's *true* points, not to markers: in the standing posture (facing +x, every
reference frame the global axes) each frame is a fixed rotation ``F_b`` spanned by the true joint centres and
landmarks, and while walking it is ``S_b(t) · F_b`` with ``S_b`` the body's own rotation from its 27 coordinates
(forward kinematics). No marker, filter, pose fit or joint-centre estimate enters.

Two definitions, as the ``idyn`` stage applies them (``gaitcli/kinematics/anatomical.py`` documents the angles):

* ISB / Cappozzo (1995), every marker set but Plug-in Gait: pelvis y from the right to the left ASIS, x anterior
  in the plane of the ASIS and the mid-PSIS; thigh z from the knee to the hip centre, y towards the left in the
  plane of the hip centre and the epicondyles; shank z from the ankle to the knee centre, y towards the left
  along the malleoli; foot x from the calcaneus to the mid-metatarsal heads, y towards the left in their plane.
* Plug-in Gait (CGM 1.0, Davis et al. 1991; Vicon's Plug-in Gait reference guide): pelvis as above; thigh z from
  the knee to the hip centre, y along the knee's flexion axis (the knee centre → lateral knee marker line the
  marker is placed on); shank z from the ankle to the knee centre, y along the ankle's axis (ankle centre →
  lateral malleolus marker); foot: Vicon's axes (x up, y left, z from the toe to the heel) on the true ankle
  centre, the toe marker and the shank's flexion axis in each frame, turned by the static foot offsets that
  bring its long axis onto the heel → toe line of the standing posture (plantarflexion about y, then rotation
  about x; no flat-foot option). This foot frame is not fixed in the foot: it follows the shank's flexion axis,
  as Plug-in Gait's does.

A Plug-in Gait subject of ``gait synth`` is built so that Plug-in Gait's own assumptions hold on it
(:func:`plug_in_gait_template`): its hip centres are where Davis's regression puts them, and the lateral knee and
ankle markers sit on the flexion axes at right angles to the segment axes, so that the chord method finds the true
knee and ankle centres. Then Plug-in Gait's frames from noise-free markers are these true frames.

Angles in rad, :data:`gaitcli.kinematics.anatomical.ANATOMICAL_ANGLES` order and senses (decomposed here, not by
the package's decomposition): every joint the Cardan y-x-z sequence of the distal frame in the proximal one
(Grood & Suntay), the pelvis and foot progression against the progression frame (the synthetic walk goes along +x).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

#: Vicon's foot axes (x up, y left, z toe → heel) written in the common segment axes (x forward, y left, z up)
VICON_FOOT_IN_SEGMENT = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
SIDES = ("r", "l")
#: the right side's lateral direction is −y
LATERAL = {"r": -1.0, "l": 1.0}


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _axes(first: np.ndarray, second: np.ndarray, order: str) -> np.ndarray:
    """Right-handed frame (..., 3, 3), columns its axes: ``order`` names the axis ``first`` gives exactly and the
    axis ``second`` gives after removing its part along ``first`` (``"zy"``, ``"yx"``, ``"xy"``)."""
    a = _unit(first)
    b = _unit(second - np.sum(second * a, axis=-1, keepdims=True) * a)
    if order == "zy":  # x = y × z
        x, y, z = np.cross(b, a), b, a
    elif order == "yx":  # z = x × y
        x, y, z = b, a, np.cross(b, a)
    elif order == "xy":  # z = x × y
        x, y, z = a, b, np.cross(a, b)
    else:
        raise ValueError(order)
    return np.stack([x, y, z], axis=-1)


def davis_hip_centres_m(template: Mapping[str, np.ndarray], *, leg_length_m: float,
                        marker_radius_m: float) -> dict[str, np.ndarray]:
    """Where Davis et al. (1991) put the hip centres of a subject standing as ``template`` (facing +x, pelvis
    level): from the mid-ASIS point C·cosθ·sinβ − (X + r)·cosβ forward, −C·cosθ·cosβ − (X + r)·sinβ up and
    half the inter-ASIS distance − C·sinθ laterally; θ = 0.5 rad, β = 0.314 rad, C = 0.115·LL − 15.3 mm,
    X = 0.1288·LL − 48.56 mm (LL leg length, r the marker radius; Plug-in Gait's reference guide)."""
    theta, beta = 0.5, 0.314
    C = 0.115 * leg_length_m - 0.0153
    X = 0.1288 * leg_length_m - 0.04856
    mid = (template["ASISr"] + template["ASISl"]) / 2
    half_width = np.linalg.norm(template["ASISl"] - template["ASISr"]) / 2
    forward = C * np.cos(theta) * np.sin(beta) - (X + marker_radius_m) * np.cos(beta)
    up = -C * np.cos(theta) * np.cos(beta) - (X + marker_radius_m) * np.sin(beta)
    return {f"HJC{s}": mid + np.array([forward, LATERAL[s] * (half_width - C * np.sin(theta)), up]) for s in SIDES}


def plug_in_gait_template(template: Mapping[str, np.ndarray], *,
                          hip_centres_m: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The standing template of a Plug-in Gait subject: each pair of femoral epicondyles (``LEF``, ``MEF``) turned
    about the knee centre (their midpoint) in the plane of the thigh's axis and the lateral direction, until it is
    at a right angle to the thigh's axis (hip → knee centre); their midpoint and distance stay. The lateral one is
    Plug-in Gait's KNE, on the knee's flexion axis at a right angle to the thigh, as the chord method takes it."""
    out = dict(template)
    for s in SIDES:
        knee = (template[f"LEF{s}"] + template[f"MEF{s}"]) / 2
        axis = _unit(hip_centres_m[f"HJC{s}"] - knee)
        lateral = np.array([0.0, LATERAL[s], 0.0])
        lateral = _unit(lateral - np.dot(lateral, axis) * axis)
        half = np.linalg.norm(template[f"LEF{s}"] - template[f"MEF{s}"]) / 2
        out[f"LEF{s}"], out[f"MEF{s}"] = knee + half * lateral, knee - half * lateral
    return out


def standing_frames(template: Mapping[str, np.ndarray], joint_centres_m: Mapping[str, np.ndarray], *,
                    plug_in_gait: Mapping[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """Each segment's anatomical frame (3, 3) in the standing posture from the true joint centres and landmarks:
    ISB, or with ``plug_in_gait`` (the lateral ankle marker ``ANKr`` and toe ``TOEr`` by model side) the CGM's
    thigh and shank (the foot's frame moves with the shank: :func:`anatomical_frames`)."""
    t, J = template, joint_centres_m
    F = {"pelvis": _axes(t["ASISl"] - t["ASISr"],
                         (t["ASISr"] + t["ASISl"]) / 2 - (t["PSISr"] + t["PSISl"]) / 2, "yx")}
    for s in SIDES:
        leftward = LATERAL[s]  # (lateral − medial point) · LATERAL points left on either side
        if plug_in_gait is None:
            F[f"thigh_{s}"] = _axes(J[f"HJC{s}"] - J[f"KJC{s}"], leftward * (t[f"LEF{s}"] - t[f"MEF{s}"]), "zy")
            F[f"shank_{s}"] = _axes(J[f"KJC{s}"] - J[f"AJC{s}"], leftward * (t[f"LM{s}"] - t[f"MM{s}"]), "zy")
            heads = (t[f"VM{s}"] + t[f"FM{s}"]) / 2
            F[f"foot_{s}"] = _axes(heads - t[f"CA{s}"], leftward * (t[f"VM{s}"] - t[f"FM{s}"]), "xy")
        else:
            F[f"thigh_{s}"] = _axes(J[f"HJC{s}"] - J[f"KJC{s}"], leftward * (t[f"LEF{s}"] - J[f"KJC{s}"]), "zy")
            F[f"shank_{s}"] = _axes(J[f"KJC{s}"] - J[f"AJC{s}"], leftward * (plug_in_gait[f"ANK{s}"] - J[f"AJC{s}"]),
                                    "zy")
    return F


def _vicon_foot(toe_to_ankle: np.ndarray, flexion_axis: np.ndarray) -> np.ndarray:
    """Vicon's foot axes: z along ``toe_to_ankle``, x = flexion axis × z (up), y = z × x."""
    z = _unit(toe_to_ankle)
    x = _unit(np.cross(flexion_axis, z))
    return np.stack([x, np.cross(z, x), z], axis=-1)


def static_foot_offsets_rad(ankle: np.ndarray, toe: np.ndarray, heel: np.ndarray,
                            flexion_axis: np.ndarray) -> tuple[float, float]:
    """(plantarflexion, rotation) rad: the turn ``Ry(p) · Rx(r)`` of the foot frame on the ankle centre and toe
    that brings its z axis onto the toe → heel line (the standing posture's, as Plug-in Gait's static does)."""
    w = _vicon_foot(ankle - toe, flexion_axis).T @ _unit(heel - toe)
    return float(np.arctan2(w[0], w[2])), float(np.arcsin(-w[1]))


def _rot_y(a: float) -> np.ndarray:
    return np.array([[np.cos(a), 0.0, np.sin(a)], [0.0, 1.0, 0.0], [-np.sin(a), 0.0, np.cos(a)]])


def _rot_x(a: float) -> np.ndarray:
    return np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), -np.sin(a)], [0.0, np.sin(a), np.cos(a)]])


def anatomical_frames(rotation: Mapping[str, np.ndarray], standing: Mapping[str, np.ndarray], *,
                      plug_in_gait: Mapping[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
    """True anatomical frames (n, 3, 3) per segment: ``S_b(t) · F_b`` from the body's rotations ``rotation[b]``
    (n, 3, 3; the identity standing) and :func:`standing_frames`. With ``plug_in_gait`` (``ANKr``, ``TOEr``,
    ``HEEr``, the true ``AJCr`` by model side, standing positions) the feet are Vicon's (x up, y left, z toe →
    heel): the foot's long axis (toe → ankle centre, fixed in the foot) and the shank's flexion axis in each
    frame, turned by the static offsets."""
    out = {b: rotation[b] @ F for b, F in standing.items()}
    if plug_in_gait is None:
        return out
    p = plug_in_gait
    for s in SIDES:
        flexion_axis = standing[f"shank_{s}"][:, 1]
        plantarflexion, turn = static_foot_offsets_rad(p[f"AJC{s}"], p[f"TOE{s}"], p[f"HEE{s}"], flexion_axis)
        long_axis = np.einsum("nij,j->ni", rotation[f"foot_{s}"], p[f"AJC{s}"] - p[f"TOE{s}"])
        out[f"vicon_foot_{s}"] = (_vicon_foot(long_axis, out[f"shank_{s}"][..., 1])
                                  @ _rot_y(plantarflexion) @ _rot_x(turn))
    return out


def _cardan_yxz(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """(n, 3) angles (a, b, c) of ``distal = proximal · Ry(a) Rx(b) Rz(c)``: a = atan2(R02, R22), b = −asin(R12),
    c = atan2(R10, R11) of R = proximalᵀ distal."""
    R = np.swapaxes(proximal, -1, -2) @ distal
    return np.stack([np.arctan2(R[..., 0, 2], R[..., 2, 2]), np.arcsin(np.clip(-R[..., 1, 2], -1.0, 1.0)),
                     np.arctan2(R[..., 1, 0], R[..., 1, 1])], axis=-1)


def anatomical_angles(frames: Mapping[str, np.ndarray]) -> np.ndarray:
    """(n, 23) rad in ``ANATOMICAL_ANGLES`` order from :func:`anatomical_frames`: pelvis tilt (anterior), obliquity
    (right side up), rotation (right side forward) against the progression frame; per side hip and knee flexion,
    adduction, internal rotation; ankle dorsiflexion, inversion, internal rotation and the foot's progression
    (toes in). The ISB ankle: y-x-z of the foot (x forward, z up) in the shank; Plug-in Gait's (``vicon_foot_r``
    present): y-x-z of Vicon's foot in the shank, dorsiflexion −(a + 90°), rotation about the floating axis,
    inversion the negative of the turn about the toe → heel axis; progression: the foot in Vicon's axes, y-x-z in
    the progression frame, its turn about the floating axis."""
    pelvis = frames["pelvis"]
    level = np.broadcast_to(np.eye(3), pelvis.shape)
    p = _cardan_yxz(level, pelvis)
    columns = [p[:, 0], -p[:, 1], p[:, 2]]
    for s in SIDES:
        m = 1.0 if s == "r" else -1.0  # the left side mirrored
        hip = _cardan_yxz(pelvis, frames[f"thigh_{s}"])
        knee = _cardan_yxz(frames[f"thigh_{s}"], frames[f"shank_{s}"])
        columns += [-hip[:, 0], m * hip[:, 1], m * hip[:, 2], knee[:, 0], m * knee[:, 1], m * knee[:, 2]]
        if f"vicon_foot_{s}" in frames:
            foot = frames[f"vicon_foot_{s}"]
            ankle = _cardan_yxz(frames[f"shank_{s}"], foot)
            columns += [-ankle[:, 0] - np.pi / 2, -m * ankle[:, 2], m * ankle[:, 1],
                        m * _cardan_yxz(level, foot)[:, 1]]
        else:
            foot = frames[f"foot_{s}"]
            ankle = _cardan_yxz(frames[f"shank_{s}"], foot)
            columns += [-ankle[:, 0], m * ankle[:, 1], m * ankle[:, 2],
                        m * _cardan_yxz(level, foot @ VICON_FOOT_IN_SEGMENT)[:, 1]]
    return np.stack(columns, axis=-1)
