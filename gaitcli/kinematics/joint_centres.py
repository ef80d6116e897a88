"""Joint centres and anatomical frames from landmarks (3.2.1, 3.3; Bell 1989/1990; Cappozzo 1995).

* Hip: Bell et al.'s regression in the pelvis frame, ``"bell1990"`` (the dissertation's,
  default) or ``"bell1989"``; or, for labs that use them, ``"harrington"`` (2007),
  ``"hara"`` (2016) and ``"davis"`` (1991, Plug-in Gait's). Coefficients and sources:
  docs/model_constants.md §2.
* Knee: midpoint of the femoral epicondyle markers LEF and MEF (3.2.1). Without the
  medial marker, Plug-in Gait's chord method (:func:`chord_joint_centre`) from the hip
  centre, the thigh wand and LEF with the knee width and marker diameter.
* Ankle: "from the malleoli using de Leva's tables" (3.2.1): ``"de_leva"`` (default) the
  knee→mid-malleoli vector lengthened by de Leva's KJC→AJC / KJC→LMAL ratio (about 6 mm
  distal of the malleoli), or ``"midpoint"``. Without the medial malleolus, the chord
  method from the knee centre, the shank wand and LM with the ankle width.
* Lab-exported virtual centres ``HJCr``, ``KJCr``, ``AJCr`` (and ``l``) replace these.

Anatomical frames (model axes: x forward, y left, z up; columns of the returned
matrices are the frame's axes in global coordinates), following Cappozzo et al.
(1995) as the dissertation does: pelvis from ASIS/PSIS; thigh z from KJC to HJC,
y in the plane of HJC and the epicondyles; shank z from AJC to KJC, y in the plane
of KJC and the malleoli; foot x from CA to the mid-metatarsal heads, z normal to
the plane CA, VM, FM (without VM, x from CA to the second metatarsal head MT2, y from
the shank); HAT z from the lumbar joint to mid C7–ST, y along ACr→ACl.
All functions are vectorised over leading dimensions ``(..., 3)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from gaitcli.core.validate import one_of
from gaitcli.errors import InputError
from gaitcli.kinematics.anthropometry import DE_LEVA, normalise_sex

BELL_1990 = {"posterior": 0.19, "inferior": 0.30, "lateral": 0.36}  # from mid-ASIS, × PW
BELL_1989 = {"posterior": 0.22, "inferior": 0.30, "medial": 0.14}  # from each ASIS, × PW
_AXES = "xyz"


def unit(v) -> np.ndarray:
    """Vectors scaled to unit length along the last axis."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def frame_from_axes(primary, secondary, *, primary_axis: str, secondary_axis: str) -> np.ndarray:
    """Right-handed orthonormal frame ``(..., 3, 3)`` (columns = axes in global coordinates).

    ``primary`` gives the direction of ``primary_axis`` exactly; ``secondary`` is made
    orthogonal to it and gives ``secondary_axis``; the third axis completes the frame.
    """
    a = unit(primary)
    b = np.asarray(secondary, dtype=float)
    b = unit(b - np.sum(b * a, axis=-1, keepdims=True) * a)
    i, j = _AXES.index(primary_axis), _AXES.index(secondary_axis)
    k = 3 - i - j
    c = np.cross(a, b) if (j - i) % 3 == 1 else np.cross(b, a)
    cols = [None, None, None]
    cols[i], cols[j], cols[k] = a, b, c
    return np.stack(cols, axis=-1)


def pelvis_frame(asis_r, asis_l, psis_r, psis_l) -> tuple[np.ndarray, np.ndarray]:
    """Pelvis anatomical frame (Bell / Cappozzo): origin mid-ASIS, y along ASISr→ASISl,
    x anterior in the plane of both ASIS and the mid-PSIS, z = x × y (superior)."""
    asis_r, asis_l = np.asarray(asis_r, dtype=float), np.asarray(asis_l, dtype=float)
    origin = (asis_r + asis_l) / 2
    mid_psis = (np.asarray(psis_r, dtype=float) + np.asarray(psis_l, dtype=float)) / 2
    R = frame_from_axes(asis_l - asis_r, origin - mid_psis, primary_axis="y", secondary_axis="x")
    return origin, R


def hip_joint_centres(asis_r, asis_l, psis_r, psis_l, *, method: str = "bell1990") -> tuple[np.ndarray, np.ndarray]:
    """Right and left hip joint centres (m) by the Bell regression, ``method`` ``"bell1990"|"bell1989"``."""
    one_of(method, ("bell1990", "bell1989"), where="hip_method")
    origin, R = pelvis_frame(asis_r, asis_l, psis_r, psis_l)
    pw = np.linalg.norm(np.asarray(asis_l, dtype=float) - np.asarray(asis_r, dtype=float), axis=-1)[..., None]
    x, y, z = R[..., 0], R[..., 1], R[..., 2]
    if method == "bell1990":
        c = BELL_1990
        base = origin - pw * (c["posterior"] * x + c["inferior"] * z)
        return base - pw * c["lateral"] * y, base + pw * c["lateral"] * y
    c = BELL_1989
    shift = -pw * (c["posterior"] * x + c["inferior"] * z)
    return (np.asarray(asis_r, dtype=float) + shift + pw * c["medial"] * y,
            np.asarray(asis_l, dtype=float) + shift - pw * c["medial"] * y)


#: Harrington et al. (2007), mm, in the ISB pelvis frame at the mid-ASIS (x anterior, y superior, z lateral):
#: x = −0.24 PD − 9.9, y = −0.16 PW − 0.04 LL − 7.1, z = 0.28 PD + 0.16 PW + 7.9
#: (PW inter-ASIS, PD mid-ASIS to mid-PSIS, LL leg length ASIS to medial malleolus)
HARRINGTON_2007 = {"x": (-9.9e-3, {"PD": -0.24}), "y": (-7.1e-3, {"PW": -0.16, "LL": -0.04}),
                   "z": (7.9e-3, {"PD": 0.28, "PW": 0.16})}
#: Hara et al. (2016), mm, same frame: x = 11 − 0.063 LL, y = −9 − 0.078 LL, z = 8 + 0.086 LL
HARA_2016 = {"x": (11e-3, {"LL": -0.063}), "y": (-9e-3, {"LL": -0.078}), "z": (8e-3, {"LL": 0.086})}
REGRESSIONS = {"harrington": HARRINGTON_2007, "hara": HARA_2016}


def regression_hip_joint_centres(asis_r, asis_l, psis_r, psis_l, *, method: str,
                                 leg_length_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Right and left hip joint centres (m) by Harrington et al. (2007) or Hara et al. (2016) (``method``
    ``"harrington"``/``"hara"``), from the pelvis markers and the leg length (m, ASIS to medial malleolus).

    The regressions are given in the ISB pelvis frame (origin mid-ASIS; x anterior, y superior,
    z lateral); here x is :func:`pelvis_frame`'s x, superior its z, lateral ∓ its y (right, left).
    """
    one_of(method, tuple(REGRESSIONS), where="hip_joint_centre")
    origin, R = pelvis_frame(asis_r, asis_l, psis_r, psis_l)
    mid_psis = (np.asarray(psis_r, dtype=float) + np.asarray(psis_l, dtype=float)) / 2
    measures = {"PW": np.linalg.norm(np.asarray(asis_l, dtype=float) - np.asarray(asis_r, dtype=float), axis=-1),
                "PD": np.linalg.norm(origin - mid_psis, axis=-1), "LL": np.asarray(leg_length_m, dtype=float)}
    c = {axis: constant + sum(k * measures[name] for name, k in terms.items())
         for axis, (constant, terms) in REGRESSIONS[method].items()}
    anterior, superior, lateral = (np.asarray(c[a])[..., None] for a in "xyz")
    x, y, z = R[..., 0], R[..., 1], R[..., 2]
    base = origin + anterior * x + superior * z
    return base - lateral * y, base + lateral * y


#: Davis et al. (1991) as Plug-in Gait applies it: θ and β in rad, the ASIS–hip distance C = 0.115 LL − 15.3 mm and
#: the ASIS–trochanter distance X_dis = 0.1288 LL − 48.56 mm (LL leg length, mm)
DAVIS_1991 = {"theta_rad": 0.5, "beta_rad": 0.314, "C": (0.115, -15.3e-3), "X_dis": (0.1288, -48.56e-3)}


def davis_hip_joint_centres(asis_r, asis_l, psis_r, psis_l, *, leg_length_m: float, marker_radius_m: float,
                            asis_trochanter_m: tuple[float, float] | None = None,
                            inter_asis_m: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Right and left hip joint centres (m) by Davis et al. (1991) (Plug-in Gait), from the pelvis markers, the
    leg length (m; Plug-in Gait's mean of both legs) and the ASIS markers' radius (m), in :func:`pelvis_frame`
    (origin mid-ASIS, x anterior, y left, z up): x = C cos θ sin β − (X_dis + r) cos β, lateral (aa − C sin θ)
    with aa half the inter-ASIS distance, z = −C cos θ cos β − (X_dis + r) sin β. ``asis_trochanter_m`` (right,
    left) replaces the regression's X_dis where the lab measured it, ``inter_asis_m`` the markers' distance."""
    origin, R = pelvis_frame(asis_r, asis_l, psis_r, psis_l)
    if inter_asis_m is None:
        aa = np.linalg.norm(np.asarray(asis_l, float) - np.asarray(asis_r, float), axis=-1)[..., None] / 2
    else:
        aa = np.full(origin.shape[:-1] + (1,), inter_asis_m / 2)
    d = DAVIS_1991
    C = d["C"][0] * leg_length_m + d["C"][1]
    regression = d["X_dis"][0] * leg_length_m + d["X_dis"][1]
    th, be = d["theta_rad"], d["beta_rad"]
    x, y, z = R[..., 0], R[..., 1], R[..., 2]
    out = []
    for k, sign in enumerate((-1.0, 1.0)):
        x_dis = regression if asis_trochanter_m is None else asis_trochanter_m[k]
        anterior = C * np.cos(th) * np.sin(be) - (x_dis + marker_radius_m) * np.cos(be)
        superior = -C * np.cos(th) * np.cos(be) - (x_dis + marker_radius_m) * np.sin(be)
        out.append(origin + anterior * x + superior * z + sign * (aa - C * np.sin(th)) * y)
    return out[0], out[1]


def chord_joint_centre(proximal, wand, lateral, offset_m, rotation_rad=0.0) -> np.ndarray:
    """Plug-in Gait's chord method: the joint centre J in the plane of ``proximal`` (the joint centre above),
    ``wand`` (the segment's wand marker) and ``lateral`` (the marker on the joint's lateral side), at
    ``offset_m`` from the lateral marker (half the joint width plus the marker radius), with the segment axis
    proximal − J perpendicular to J − lateral, on the far side of the proximal–lateral line from the wand;
    that plane turned by ``rotation_rad`` about the line (Plug-in Gait's thigh and shank rotation offsets, which
    a knee alignment device measures in the static trial).

    With u the unit vector lateral → proximal (length L) and v the in-plane unit normal to it away from the
    wand, turned about u: J = lateral + δ (δ/L · u + √(1 − δ²/L²) · v) (Thales: J lies on the circle over
    that line).
    """
    proximal, wand, lateral = (np.asarray(a, dtype=float) for a in (proximal, wand, lateral))
    delta = np.asarray(offset_m, dtype=float)[..., None]
    chord = proximal - lateral
    length = np.linalg.norm(chord, axis=-1, keepdims=True)
    u = chord / length
    away = lateral - wand
    v = unit(away - np.sum(away * u, axis=-1, keepdims=True) * u)
    beta = np.asarray(rotation_rad, dtype=float)[..., None]
    v = v * np.cos(beta) + np.cross(u, v) * np.sin(beta)  # Rodrigues, v ⟂ u
    ratio = delta / length
    return lateral + delta * (ratio * u + np.sqrt(np.clip(1 - ratio ** 2, 0.0, None)) * v)


@dataclass(frozen=True)
class JointWidths:
    """Plug-in Gait's subject measurements for the chord method (m): knee and ankle widths per side
    (``{"r": ..., "l": ...}``, a side missing when unknown), the marker diameter, and each segment's wand labels
    (``{"thigh_r": ("RTHI",), ...}``: the tracking marker that, with the lateral marker, spans the chord plane;
    the first one present is used)."""

    knee_m: Mapping[str, float] = field(default_factory=dict)
    ankle_m: Mapping[str, float] = field(default_factory=dict)
    marker_diameter_m: float = 0.014
    wands: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    def offset_m(self, joint: str, side: str) -> float | None:
        """δ = (width + marker diameter) / 2 of ``joint`` ``"knee"|"ankle"`` on ``side``, None when unknown."""
        width = (self.knee_m if joint == "knee" else self.ankle_m).get(side)
        return None if width is None else (width + self.marker_diameter_m) / 2

    def chord_inputs(self, joint: str, side: str, landmarks: Mapping[str, np.ndarray]):
        """(wand position, δ) for the chord of ``joint`` on ``side``, or None when the width or the wand is missing."""
        labels = self.wands.get(f"{'thigh' if joint == 'knee' else 'shank'}_{side}", ())
        wand = next((lab for lab in labels if present(landmarks, lab)), None)
        offset = self.offset_m(joint, side)
        if offset is None or wand is None:
            return None
        return np.asarray(landmarks[wand], dtype=float), offset


def functional_joint_centre(R_parent, d_parent, R_child, d_child) -> tuple[np.ndarray, np.ndarray, float, int]:
    """SCORE (Ehrig et al. 2006): the point fixed in both bodies of a joint, from their poses over frames.

    ``R_*`` (n, 3, 3) body → global rotations, ``d_*`` (n, 3) body origins (m). Minimises
    Σ_k |R_p,k c_p + d_p,k − R_c,k c_c − d_c,k|² over the point's body coordinates c_p, c_c (linear least
    squares over the frames where both poses are finite). Returns (c_p, c_c, RMS of the residual in m, and
    ``spread``: RMS × √frames / the smallest singular value, m, how far the point is uncertain along its least
    determined direction). The motion must turn the joint about more than one axis for every coordinate to
    be determined: in walking the hip turns mostly about its flexion axis, and the centre's position along
    that (mediolateral) axis is weakly determined.
    """
    R_parent, R_child = np.asarray(R_parent, float), np.asarray(R_child, float)
    d_parent, d_child = np.asarray(d_parent, float), np.asarray(d_child, float)
    ok = (np.all(np.isfinite(R_parent), axis=(1, 2)) & np.all(np.isfinite(R_child), axis=(1, 2))
          & np.all(np.isfinite(d_parent), axis=1) & np.all(np.isfinite(d_child), axis=1))
    A = np.concatenate([R_parent[ok], -R_child[ok]], axis=2).reshape(-1, 6)
    b = (d_child[ok] - d_parent[ok]).reshape(-1)
    if A.shape[0] < 6:
        raise ValueError("a functional joint centre needs poses of both bodies in at least two frames")
    solution, _, _, singular = np.linalg.lstsq(A, b, rcond=None)
    residual = (A @ solution - b).reshape(-1, 3)
    rms = float(np.sqrt(np.mean(np.sum(residual ** 2, axis=1))))
    # how far the point may move along the least determined direction for a residual of this size
    spread = float(rms * np.sqrt(A.shape[0] / 3) / singular[-1]) if singular[-1] > 0 else np.inf
    return solution[:3], solution[3:], rms, spread


def knee_joint_centre(lef, mef) -> np.ndarray:
    """Midpoint of the lateral and medial femoral epicondyle markers (3.2.1)."""
    return (np.asarray(lef, dtype=float) + np.asarray(mef, dtype=float)) / 2


def ankle_distal_ratio(sex: str = "male") -> float:
    """de Leva's KJC→AJC / KJC→LMAL length ratio (1.0145 male, 1.0146 female)."""
    rows = DE_LEVA[normalise_sex(sex)]
    return rows["shank"].length_mm / rows["shank_lmal"].length_mm


def ankle_joint_centre(lm, mm, kjc=None, *, method: str = "de_leva", sex: str = "male") -> np.ndarray:
    """Ankle joint centre from the malleoli; ``"de_leva"`` needs the knee centre ``kjc``."""
    one_of(method, ("de_leva", "midpoint"), where="ankle_method")
    mid = (np.asarray(lm, dtype=float) + np.asarray(mm, dtype=float)) / 2
    if method == "midpoint":
        return mid
    if kjc is None:
        raise ValueError("the de Leva ankle centre needs the knee joint centre")
    kjc = np.asarray(kjc, dtype=float)
    return kjc + ankle_distal_ratio(sex) * (mid - kjc)


def present(landmarks: Mapping[str, np.ndarray], name: str) -> bool:
    """True if ``name`` is in ``landmarks`` and seen in at least one frame."""
    return name in landmarks and bool(np.any(np.isfinite(landmarks[name])))


def _need(landmarks: Mapping[str, np.ndarray], name: str, purpose: str, source) -> np.ndarray:
    if not present(landmarks, name):
        raise InputError(source, name, f"marker missing from the static trial (needed for {purpose})")
    return np.asarray(landmarks[name], dtype=float)


def leg_length_m(landmarks: Mapping[str, np.ndarray], source=None) -> float:
    """Mean leg length (m) of the two sides, ASIS to medial malleolus (as Harrington, Hara and Davis measured it);
    to the lateral malleolus where a set has no medial marker (Plug-in Gait)."""
    sides = []
    for s in ("r", "l"):
        malleolus = next((m for m in (f"MM{s}", f"LM{s}") if present(landmarks, m)), None)
        if malleolus is not None and present(landmarks, f"ASIS{s}"):
            sides.append(np.linalg.norm(np.asarray(landmarks[f"ASIS{s}"], float)
                                        - np.asarray(landmarks[malleolus], float), axis=-1))
    if not sides:
        raise InputError(source, "leg_length_m", "the hip regression needs the leg length: no malleolus markers "
                                                 "(MMr, MMl or LMr, LMl) in the static trial (expected leg_length_m "
                                                 "in subject.yaml, or the C3D's PROCESSING:LeftLegLength)")
    return float(np.mean(sides))


def joint_centres(landmarks: Mapping[str, np.ndarray], *, hip_method: str = "bell1990",
                  ankle_method: str = "de_leva", sex: str = "male", leg_length: float | None = None,
                  widths: JointWidths | None = None, source: str | Path | None = None) -> dict[str, np.ndarray]:
    """``HJCr, HJCl, KJCr, KJCl, AJCr, AJCl`` from landmark positions.

    A virtual joint centre present in ``landmarks`` is used as is; otherwise it is
    estimated (Bell or a regression; epicondyle midpoint and malleoli, or the chord method
    where the medial marker is absent and ``widths`` gives the joint's width and wand).

    Parameters
    ----------
    landmarks : mapping of str to array_like
        Model landmark → position (..., 3), m.
    hip_method : str
        ``"bell1990"``, ``"bell1989"``, ``"harrington"``, ``"hara"`` or ``"davis"``.
    ankle_method : str
        ``"de_leva"`` or ``"midpoint"`` (:func:`ankle_joint_centre`).
    sex : str
        de Leva's table for the ankle.
    leg_length : float, optional
        For the regressions, m (default: :func:`leg_length_m` of the landmarks).
    widths : JointWidths, optional
        For the chord method.
    source : str or Path, optional
        The file, for messages.

    Returns
    -------
    dict of str to numpy.ndarray
        The six centres (..., 3), m.

    Raises
    ------
    InputError
        Naming the first marker an estimate needs but ``landmarks`` lacks.
    """
    widths = widths or JointWidths()
    out: dict[str, np.ndarray] = {}
    if not (present(landmarks, "HJCr") and present(landmarks, "HJCl")):
        pelvis = [_need(landmarks, n, "the hip joint centres", source) for n in ("ASISr", "ASISl", "PSISr", "PSISl")]
        if hip_method in REGRESSIONS or hip_method == "davis":
            length = leg_length_m(landmarks, source) if leg_length is None else leg_length
        if hip_method in REGRESSIONS:
            out["HJCr"], out["HJCl"] = regression_hip_joint_centres(*pelvis, method=hip_method, leg_length_m=length)
        elif hip_method == "davis":
            out["HJCr"], out["HJCl"] = davis_hip_joint_centres(*pelvis, leg_length_m=length,
                                                               marker_radius_m=widths.marker_diameter_m / 2)
        else:
            out["HJCr"], out["HJCl"] = hip_joint_centres(*pelvis, method=hip_method)
    for s in ("r", "l"):
        if present(landmarks, f"HJC{s}"):
            out[f"HJC{s}"] = np.asarray(landmarks[f"HJC{s}"], dtype=float)
        chord = widths.chord_inputs("knee", s, landmarks)
        if present(landmarks, f"KJC{s}"):
            out[f"KJC{s}"] = np.asarray(landmarks[f"KJC{s}"], dtype=float)
        elif chord is not None and not present(landmarks, f"MEF{s}"):
            out[f"KJC{s}"] = chord_joint_centre(out[f"HJC{s}"], chord[0],
                                                _need(landmarks, f"LEF{s}", "the knee joint centre", source), chord[1])
        else:
            out[f"KJC{s}"] = knee_joint_centre(_need(landmarks, f"LEF{s}", "the knee joint centre", source),
                                               _need(landmarks, f"MEF{s}", "the knee joint centre", source))
        chord = widths.chord_inputs("ankle", s, landmarks)
        if present(landmarks, f"AJC{s}"):
            out[f"AJC{s}"] = np.asarray(landmarks[f"AJC{s}"], dtype=float)
        elif chord is not None and not present(landmarks, f"MM{s}"):
            out[f"AJC{s}"] = chord_joint_centre(out[f"KJC{s}"], chord[0],
                                                _need(landmarks, f"LM{s}", "the ankle joint centre", source), chord[1])
        else:
            out[f"AJC{s}"] = ankle_joint_centre(_need(landmarks, f"LM{s}", "the ankle joint centre", source),
                                                _need(landmarks, f"MM{s}", "the ankle joint centre", source),
                                                out[f"KJC{s}"], method=ankle_method, sex=sex)
    return {k: out[k] for k in ("HJCr", "HJCl", "KJCr", "KJCl", "AJCr", "AJCl")}


def _leftward(lateral, medial, side: str) -> np.ndarray:
    """Vector pointing to the subject's left from a lateral/medial landmark pair of ``side``."""
    sign = 1.0 if side == "l" else -1.0
    return sign * (np.asarray(lateral, dtype=float) - np.asarray(medial, dtype=float))


_GLOBAL_Y = np.array([0.0, 1.0, 0.0])


def thigh_frame(hjc, kjc, lef=None, mef=None, *, side: str) -> np.ndarray:
    """Thigh anatomical axes: z from KJC to HJC, y leftward in the plane of HJC, LEF, MEF
    (global y when the epicondyles are not available), x = y × z (anterior)."""
    hjc, kjc = np.asarray(hjc, dtype=float), np.asarray(kjc, dtype=float)
    ml = _GLOBAL_Y if lef is None or mef is None else _leftward(lef, mef, side)
    return frame_from_axes(hjc - kjc, np.broadcast_to(ml, hjc.shape), primary_axis="z", secondary_axis="y")


def shank_frame(kjc, ajc, lm=None, mm=None, *, side: str) -> np.ndarray:
    """Shank anatomical axes: z from AJC to KJC, y leftward along the malleoli (global y
    when they are not available), x = y × z (anterior)."""
    kjc, ajc = np.asarray(kjc, dtype=float), np.asarray(ajc, dtype=float)
    ml = _GLOBAL_Y if lm is None or mm is None else _leftward(lm, mm, side)
    return frame_from_axes(kjc - ajc, np.broadcast_to(ml, kjc.shape), primary_axis="z", secondary_axis="y")


def foot_frame(ca, vm, fm, *, side: str) -> np.ndarray:
    """Foot anatomical axes: x from CA to the mid-metatarsal heads, y leftward in the plane
    CA, VM, FM, z = x × y (dorsal)."""
    ca, vm, fm = (np.asarray(a, dtype=float) for a in (ca, vm, fm))
    return frame_from_axes((vm + fm) / 2 - ca, _leftward(vm, fm, side), primary_axis="x", secondary_axis="y")


def toe_foot_frame(ca, toe, shank_axes) -> np.ndarray:
    """Foot anatomical axes without a fifth metatarsal marker (Plug-in Gait's HEE/TOE foot): x from CA to the toe
    marker (second metatarsal head), y the shank's leftward axis made orthogonal to it, z = x × y (dorsal)."""
    ca, toe = np.asarray(ca, dtype=float), np.asarray(toe, dtype=float)
    return frame_from_axes(toe - ca, np.asarray(shank_axes, dtype=float)[..., 1], primary_axis="x", secondary_axis="y")


def trunk_frame(lumbar, c7, st, ac_r, ac_l) -> np.ndarray:
    """HAT anatomical axes: z from the lumbar joint to mid C7–ST, y along ACr→ACl, x = y × z."""
    top = (np.asarray(c7, dtype=float) + np.asarray(st, dtype=float)) / 2
    return frame_from_axes(top - np.asarray(lumbar, dtype=float), np.asarray(ac_l, dtype=float) - ac_r,
                           primary_axis="z", secondary_axis="y")
