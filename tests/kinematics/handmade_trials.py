"""Trial folders built by hand from geometry, for the known-answer tests of the clinical signs.

Nothing here uses :mod:`gaitcli.kinematics.conventions` or any gaitcli function that calls it:
the skeleton, the joint centres, the rotations and the plate wrenches are plain numpy. The only
gaitcli code used is the C3D writer and its two containers (``Markers``, ``ForcePlate``).

Model axes: x forward, y to the subject's left, z up; metres. Lateral is −y on the right side
and +y on the left side.

The standing skeleton (:func:`standing_skeleton`) places the pelvis level (both ASIS and both
PSIS at one height), so the pelvis frame of Bell / Cappozzo is the global frame, and the joint
centres the model will estimate follow from the published formulas, computed here by hand:

* hip (Bell et al. 1990): from the mid-ASIS point, 0.19·PW posterior, 0.30·PW inferior and
  0.36·PW lateral, PW the inter-ASIS distance;
* knee: midpoint of the epicondyle markers LEF, MEF;
* ankle (de Leva 1996, male): the knee → mid-malleoli vector lengthened by KJC→AJC / KJC→LMAL
  = 440.3 / 434.0 mm, i.e. about 6 mm below the malleoli.

Each leg is built on the vertical line through its hip centre (knee and ankle centres straight
below it), the foot ahead of the ankle. A pose rotates each segment's markers rigidly about the
joint centre it hangs from (hip, knee, ankle), so the joint centres of the posed skeleton are
exactly where the model puts them and the independently fitted segments still meet.

Joint rotations are written in the model's own axes: a rotation by ``a`` about +y turns +x
(forward) towards −z, i.e. the knee backwards (hip extension), the shank's distal end forwards
(knee *extension* is about −y), the toes down (plantarflexion). Clinical flexion / dorsiflexion
is therefore a rotation about −y for the hip and the ankle, about +y for the knee. About +x, the
knee (below the hip) moves towards +y: adduction of the right hip, abduction of the left. About
+z, the front of the thigh turns towards +y: internal rotation of the right hip, external of the
left.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gaitcli.core.recording import ForcePlate, Markers
from gaitcli.io.c3d_write import write_c3d

SIDES = ("r", "l")
LATERAL = {"r": -1.0, "l": 1.0}  # sign of y pointing laterally
MARKER_RATE_HZ = 100.0
ANALOG_RATE_HZ = 1000.0
G = 9.81

# Bell et al. (1990) hip regression, × inter-ASIS distance; de Leva (1996) male shank ratio
BELL_POSTERIOR, BELL_INFERIOR, BELL_LATERAL = 0.19, 0.30, 0.36
DE_LEVA_ANKLE_RATIO = 440.3 / 434.0

SUBJECT_YAML = "mass_kg: 70.0\nstature_m: 1.70\nsex: male\n"
MASS_KG, STATURE_M = 70.0, 1.70

THIGH_MARKERS = ("GT", "MRF", "LEF", "MEF")
SHANK_MARKERS = ("TT", "LM", "MM")
FOOT_MARKERS = ("CA", "VM", "FM")


def rot_x(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def bell_1990_hip_centres(asis_r, asis_l, psis_r, psis_l) -> dict[str, np.ndarray]:
    """Bell 1990 hip centres, by hand, for a pelvis whose frame is built from these four points."""
    origin = (asis_r + asis_l) / 2
    y = (asis_l - asis_r) / np.linalg.norm(asis_l - asis_r)
    back = origin - (psis_r + psis_l) / 2
    x = back - np.dot(back, y) * y
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    pw = np.linalg.norm(asis_l - asis_r)
    base = origin - pw * (BELL_POSTERIOR * x + BELL_INFERIOR * z)
    return {"r": base - pw * BELL_LATERAL * y, "l": base + pw * BELL_LATERAL * y}


def standing_skeleton() -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """The 28 Table A.6 markers of an upright 1.70 m subject facing +x, and the joint centres by hand.

    Returns ``(markers, centres)``: ``markers[name]`` (3,) and ``centres`` with ``HJCr``,
    ``KJCr``, ``AJCr`` (and ``l``), all in metres.
    """
    m: dict[str, np.ndarray] = {}
    pw = 0.24  # inter-ASIS distance
    m["ASISr"], m["ASISl"] = np.array([0.06, -pw / 2, 0.98]), np.array([0.06, pw / 2, 0.98])
    m["PSISr"], m["PSISl"] = np.array([-0.11, -0.045, 0.98]), np.array([-0.11, 0.045, 0.98])
    hips = bell_1990_hip_centres(m["ASISr"], m["ASISl"], m["PSISr"], m["PSISl"])
    centres = {}
    for s in SIDES:
        lat = LATERAL[s]
        h = hips[s]
        knee = h + np.array([0.0, 0.0, -0.42])
        mid_malleoli = knee + np.array([0.0, 0.0, -0.40])
        ankle = knee + DE_LEVA_ANKLE_RATIO * (mid_malleoli - knee)
        centres[f"HJC{s}"], centres[f"KJC{s}"], centres[f"AJC{s}"] = h, knee, ankle

        def at(dx, dy_lateral, z, base=h, lat=lat):
            return np.array([base[0] + dx, base[1] + lat * dy_lateral, z])

        m[f"GT{s}"] = at(0.0, 0.08, h[2] - 0.02)
        m[f"MRF{s}"] = at(0.07, 0.0, knee[2] + 0.25)
        m[f"LEF{s}"] = at(0.0, 0.05, knee[2])
        m[f"MEF{s}"] = at(0.0, -0.05, knee[2])  # KJC = mid-epicondyles
        m[f"TT{s}"] = at(0.045, 0.0, knee[2] - 0.07)
        m[f"LM{s}"] = at(0.0, 0.035, mid_malleoli[2])
        m[f"MM{s}"] = at(0.0, -0.035, mid_malleoli[2])  # mid-malleoli straight below KJC
        # a level foot, its long axis along +x: the foot's anatomical frame (CA → mid-metatarsals, y in the
        # plane of CA, VM, FM) is the global one, so the standing ankle reads 0° in all three planes
        m[f"CA{s}"] = at(-0.06, 0.0, 0.02)
        m[f"VM{s}"] = at(0.145, 0.0325, 0.02)
        m[f"FM{s}"] = at(0.145, -0.0325, 0.02)
        m[f"AC{s}"] = np.array([-0.02, lat * 0.18, 1.42])
    m["C7"] = np.array([-0.08, 0.0, 1.46])
    m["ST"] = np.array([0.08, 0.0, 1.40])
    return m, centres


def pose_skeleton(markers, centres, leg_rotations) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Rotate each leg's segments about their joint centres.

    ``leg_rotations[side] = (R_hip, R_knee, R_ankle)``: the rotation of the thigh relative to the
    (unmoved) pelvis, of the shank relative to the thigh and of the foot relative to the shank,
    each a 3×3 matrix in model axes. Returns the posed markers and joint centres.
    """
    out = {k: v.copy() for k, v in markers.items()}
    jc = {k: v.copy() for k, v in centres.items()}
    for s, (r_hip, r_knee, r_ankle) in leg_rotations.items():
        hjc, kjc, ajc = centres[f"HJC{s}"], centres[f"KJC{s}"], centres[f"AJC{s}"]
        thigh = r_hip
        shank = thigh @ r_knee
        foot = shank @ r_ankle
        new_kjc = hjc + thigh @ (kjc - hjc)
        new_ajc = new_kjc + shank @ (ajc - kjc)
        for d in THIGH_MARKERS:
            out[d + s] = hjc + thigh @ (markers[d + s] - hjc)
        for d in SHANK_MARKERS:
            out[d + s] = new_kjc + shank @ (markers[d + s] - kjc)
        for d in FOOT_MARKERS:
            out[d + s] = new_ajc + foot @ (markers[d + s] - ajc)
        jc[f"KJC{s}"], jc[f"AJC{s}"] = new_kjc, new_ajc
    return out, jc


def to_markers(landmarks: dict[str, np.ndarray], frames: int) -> Markers:
    """A motionless recording of ``landmarks`` over ``frames`` frames at 100 Hz."""
    labels = tuple(landmarks)
    one = np.stack([landmarks[k] for k in labels])  # (markers, 3)
    return Markers(labels, np.repeat(one[None], frames, axis=0), MARKER_RATE_HZ)


def vertical_load_plate(name: str, centre_xy, force_N: float, cop_xy, frames: int, *,
                        free_moment_Nm: float = 0.0, half_size=(0.25, 0.08)) -> ForcePlate:
    """A plate (top surface at z = 0) carrying a constant vertical force at ``cop_xy`` and a free moment.

    The wrench is stored as the C3D writer expects: the force the ground exerts on the subject
    and its moment about the centre of the plate's top surface, ``(COP − centre) × F`` plus the
    vertical free moment ``free_moment_Nm`` (about +z, the ground's twist on the foot).
    """
    centre = np.array([centre_xy[0], centre_xy[1], 0.0])
    hx, hy = half_size
    corners = centre + np.array([[hx, -hy, 0.0], [-hx, -hy, 0.0], [-hx, hy, 0.0], [hx, hy, 0.0]])
    if not (abs(cop_xy[0] - centre[0]) < hx and abs(cop_xy[1] - centre[1]) < hy):
        raise ValueError("the centre of pressure must lie on the plate")
    n = frames * int(ANALOG_RATE_HZ / MARKER_RATE_HZ)
    force = np.tile([0.0, 0.0, force_N], (n, 1))
    lever = np.array([cop_xy[0], cop_xy[1], 0.0]) - centre
    moment = np.tile(np.cross(lever, [0.0, 0.0, force_N]) + [0.0, 0.0, free_moment_Nm], (n, 1))
    return ForcePlate(name=name, force_N=force, moment_Nm=moment, centre_m=centre, corners_m=corners,
                      rate_hz=ANALOG_RATE_HZ)


def write_folder(folder: Path, static: dict[str, np.ndarray], dynamic: dict[str, np.ndarray], *,
                 frames: int = 40, plates=(), subject: str = SUBJECT_YAML) -> Path:
    """A trial folder: static.c3d (1 s of ``static``), trial.c3d (``dynamic`` + ``plates``), subject.yaml."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    write_c3d(folder / "static.c3d", to_markers(static, int(MARKER_RATE_HZ)), [])
    write_c3d(folder / "trial.c3d", to_markers(dynamic, frames), list(plates))
    (folder / "subject.yaml").write_text(subject)
    return folder
