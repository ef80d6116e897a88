"""The one place where the model's mathematical signs become the clinical signs of the output tables.

Internally (x forward, y left, z up, Cardan y-x-z joint angles (3.1)) a positive
rotation about y is hip extension, knee flexion and ankle plantarflexion, and the
left side's adduction and internal rotation are negative rotations. Output tables
follow the clinical convention on both sides alike: hip and knee flexion, ankle
dorsiflexion, adduction and internal rotation positive, and every joint moment
positive in the same sense as its angle (the moment the proximal segment exerts
on the distal one). Pelvis angles and the lumbar joint keep the model's signs
(lumbar: forward flexion, left bending, left rotation positive).

The sagittal joint angles of the 2-D models (limb, predict) are the clinical
ones: hip flexion relative to the pelvis/HAT, knee flexion, ankle dorsiflexion
(0 with the foot ⟂ shank), in rad. Two published models read them with other
signs; :func:`muscle_path_angles` and :func:`riener_edrich_angles` /
:func:`riener_edrich_moments` are the only conversions (pure arithmetic, so
they work on numpy arrays and CasADi SX alike).
"""

from __future__ import annotations

import numpy as np

from gaitcli.kinematics.anatomical import ANATOMICAL_ANGLES
from gaitcli.kinematics.model import JOINTS

#: sign per joint and axis (flexion about y, adduction about x, rotation about z): clinical = sign · model
CLINICAL_SIGN = {
    "lumbar": (1.0, 1.0, 1.0),
    "hip_r": (-1.0, 1.0, 1.0), "knee_r": (1.0, 1.0, 1.0), "ankle_r": (-1.0, 1.0, 1.0),
    "hip_l": (-1.0, -1.0, -1.0), "knee_l": (1.0, -1.0, -1.0), "ankle_l": (-1.0, -1.0, -1.0),
}
SIGNS = np.array([CLINICAL_SIGN[j] for j in JOINTS])  # (7, 3)
CONVENTION = ("clinical: hip/knee flexion, ankle dorsiflexion, adduction and internal rotation positive on both "
              "sides; moments positive in the sense of their angle; pelvis and lumbar in model signs")


def coordinates_to_clinical(q: np.ndarray) -> np.ndarray:
    """Coordinates (n, 27) in m and rad, model signs → m and degrees, clinical signs."""
    out = np.array(q, dtype=float, copy=True)
    out[:, 3:6] = np.degrees(out[:, 3:6])
    out[:, 6:] = np.degrees(out[:, 6:]) * SIGNS.reshape(-1)
    return out


ANATOMICAL_CONVENTION = ("anatomical (Cardan y-x-z between anatomical frames): hip/knee flexion, ankle dorsiflexion, "
                         "adduction and internal rotation positive on both sides; ankle inversion as Plug-in Gait's "
                         "AnkleAngles Y (Vicon Nexus's sign: the turn about the foot's toe-to-heel axis); pelvis "
                         "against the direction of progression as Plug-in Gait's right side (anterior tilt, right "
                         "side up, right side forward positive); foot progression internal positive")
#: the sign that takes :func:`gaitcli.kinematics.anatomical.anatomical_angles`' ankle inversion (rad, the sole
#: turned medially positive) to the tables' (Plug-in Gait's AnkleAngles Y, which Vicon Nexus calls inversion and
#: reports as the turn about the foot's toe → heel axis: checked on Vicon's own outputs by benchmarks/bench_pig.py)
PIG_ANKLE_INVERSION_SIGN = -1.0
#: the columns of the anatomical angles that :func:`anatomical_to_degrees` turns to Plug-in Gait's sign
PIG_SIGNED_ANGLES = ("ankle_r_inversion", "ankle_l_inversion")


def anatomical_to_degrees(angles_rad: np.ndarray) -> np.ndarray:
    """Anatomical angles (..., 23) (:func:`gaitcli.kinematics.anatomical.anatomical_angles`, rad, clinical senses)
    → degrees for people (:data:`ANATOMICAL_CONVENTION`): the ankle inversion in Plug-in Gait's sign
    (:data:`PIG_ANKLE_INVERSION_SIGN`), as Vicon Nexus, its C3D outputs and Plug-in Gait bands report it."""
    out = np.degrees(np.asarray(angles_rad, dtype=float))
    for name in PIG_SIGNED_ANGLES:
        out[..., ANATOMICAL_ANGLES.index(name)] *= PIG_ANKLE_INVERSION_SIGN
    return out


def moments_to_clinical(moments: np.ndarray) -> np.ndarray:
    """Joint moment vectors (n, 7, 3) as (x, y, z) components in a segment frame → (n, 21) clinical columns.

    Columns per joint: flexion (about y), adduction (about x), rotation (about z),
    each with the sign of its angle.
    """
    moments = np.asarray(moments, dtype=float)
    ordered = moments[:, :, [1, 0, 2]]  # (y, x, z) = flexion, adduction, rotation axes
    return (ordered * SIGNS).reshape(moments.shape[0], -1)



#: the positive sense of each joint's moment components in the Plug-in Gait convention (flexion, adduction,
#: rotation axes in that order): the internal moment, the opposite of "positive in the sense of its angle"
PIG_MOMENT_SENSES = {"lumbar": ("extensor", "right_bender", "right_rotator"),
                     "hip": ("extensor", "abductor", "external_rotator"),
                     "knee": ("extensor", "abductor", "external_rotator"),
                     "ankle": ("plantarflexor", "everter", "external_rotator")}
PIG_MOMENTS = tuple(f"{j}_{sense}_moment" for j in JOINTS for sense in PIG_MOMENT_SENSES[j.split("_")[0]])
PIG_CONVENTION = ("Plug-in Gait: internal moments (proximal on distal) in the distal anatomical frame; extensor "
                  "(ankle plantarflexor), abductor (ankle everter), external rotator positive")


def moments_to_plug_in_gait(moments: np.ndarray) -> np.ndarray:
    """Joint moment vectors (n, 7, 3), x, y, z components in each distal segment's anatomical frame → (n, 21)
    columns :data:`PIG_MOMENTS` (Vicon's signs: every component opposite to :func:`moments_to_clinical`)."""
    return -moments_to_clinical(moments)


def muscle_path_angles(hip_flexion, knee_flexion, ankle_dorsiflexion):
    """Sagittal joint angles (rad) → the angles (α, β, γ) of the muscle path (A.9; docs/model_constants.md §6).

    α = hip extension = −hip flexion, β = knee flexion, γ = ankle plantarflexion
    from neutral = −dorsiflexion.
    """
    return -hip_flexion, knee_flexion, -ankle_dorsiflexion


def riener_edrich_angles(hip_flexion, knee_flexion, ankle_dorsiflexion):
    """Sagittal joint angles (rad) → Riener & Edrich's (φ_H, φ_K, φ_A) in degrees (docs/model_constants.md §10).

    Their angles are hip flexion, knee flexion and ankle *plantar*flexion positive.
    """
    deg = 180.0 / np.pi
    return hip_flexion * deg, knee_flexion * deg, -ankle_dorsiflexion * deg


def riener_edrich_moments(m_hip, m_knee, m_ankle):
    """Riener & Edrich's moments (N·m, positive in the sense of their angle) → hip flexion,
    knee flexion and ankle dorsiflexion moments."""
    return m_hip, m_knee, -m_ankle


#: the sagittal joint angles of outputs for people, per side: hip flexion, knee flexion, ankle dorsiflexion
WALKER_CLINICAL = ("hip_{s}_flexion", "knee_{s}_flexion", "ankle_{s}_dorsiflexion")


def walker_joint_angles(hat, thigh, knee, ankle):
    """The predictive model's angles (Diss. 5.2: clockwise-positive, rad) of one leg → its joint angles in
    the product's senses (rad): hip flexion −(thigh − HAT) (docs/model_constants.md §13), knee flexion, ankle
    dorsiflexion −ankle (the model's ankle angle is plantarflexion-positive). Pure arithmetic: numpy or CasADi.
    """
    return -(thigh - hat), knee, -ankle


def walker_moments_to_clinical(moments: np.ndarray) -> np.ndarray:
    """The predictive model's joint moments (…, 6: hip, knee, ankle right then left, each positive in the sense of
    its model angle, ``predict.contact.joint_moment_map``) → the senses of :func:`walker_joint_angles`: hip
    flexion, knee flexion, ankle dorsiflexion positive, N·m."""
    return np.asarray(moments, dtype=float) * np.array([-1.0, 1.0, -1.0] * 2)


def walker_to_clinical(y: np.ndarray) -> np.ndarray:
    """The predictive model's coordinates (n, 9) → (n, 6) clinical sagittal angles in degrees: right hip
    flexion, knee flexion, ankle dorsiflexion, then the left's (:func:`walker_joint_angles`)."""
    y = np.atleast_2d(np.asarray(y, dtype=float))
    out = []
    for thigh, knee, ankle in ((3, 4, 5), (6, 7, 8)):
        out += list(walker_joint_angles(y[:, 2], y[:, thigh], y[:, knee], y[:, ankle]))
    return np.degrees(np.column_stack(out))
