"""The 7-body, 9-DoF planar walking model of the predictive simulations (Diss. 5.2.2).

Bodies: HAT (pelvis, trunk, head and arms as one body), and per leg thigh,
shank and foot. Coordinates ``y = (y1 … y9)`` (5.2), in the dissertation's
reading (Fig. 5.2 is lost; docs/model_constants.md §13), SI units:

    y1, y2   hip joint centre x (forward) and z (up), m (both hips at one point)
    y3       HAT angle from upright, rad
    y4, y7   right / left thigh angle from the downward vertical (absolute), rad
    y5, y8   right / left knee flexion, rad
    y6, y9   right / left ankle angle from neutral (foot ⟂ shank), rad

All angles are positive in one rotational sense, clockwise seen from the
subject's right with the walk going to the right: HAT leaning forward, thigh
*extension*, knee flexion, ankle *plantar*flexion. These signs stay inside the
predict package; outputs for people convert them once, through
:func:`gaitcli.kinematics.conventions.walker_to_clinical`.

The equations are those of :class:`gaitcli.dynamics.planar.PlanarChain` (a
floating HAT, counter-clockwise angles) with the one sign it does not share, the
HAT angle, turned at the boundary: ``q = S·y`` with ``S = diag(1, 1, −1, 1, …)``
(the thigh, knee and ankle joints carry their sign in the chain), so
``M_y = S M_q S``, ``k_y = S k_q``, ``g_y = S g_q`` and point Jacobians ``J_q S``.

Segment parameters: de Leva (1996) for the subject, as the muscle stage's limb
(:meth:`gaitcli.muscles.limb.LimbParameters.from_anthropometry`: thigh, shank,
foot); the 2-D HAT composes the 3-D model's pelvis and HAT (head, trunk, arms
crossed; :func:`gaitcli.kinematics.anthropometry.segment_parameters`) about the
hip centre, whose sagittal inertia I_yy it keeps (docs/prediction.md, "The 2-D HAT").
Contact points per foot (Fig. 5.4 is lost; gait2dc's, scaled by stature H:
docs/model_constants.md §12): heel A 0.033·H behind and MTP B 0.091·H ahead of
the ankle, both 0.039·H below it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from gaitcli.core.physics import GRAVITY_M_S2
from gaitcli.dynamics.planar import Joint, PlanarChain, Segment
from gaitcli.kinematics.anthropometry import segment_parameters
from gaitcli.muscles.limb import LimbParameters

COORDINATES = ("hip_x", "hip_z", "hat_angle", "thigh_r", "knee_r", "ankle_r", "thigh_l", "knee_l", "ankle_l")
SIDES = ("r", "l")
#: the dissertation's subject 1 (Tables A.4–A.5): body mass, stature, measured thigh and shank lengths
SUBJECT_1 = {"mass_kg": 73.0, "stature_m": 1.792, "sex": "male", "thigh_length_m": 0.475, "shank_length_m": 0.429}
#: contact points relative to the ankle, per stature (gait2dc's at H = 1.8 m: docs/model_constants.md §12)
HEEL_BEHIND_ANKLE_PER_STATURE = 0.060 / 1.8
MTP_AHEAD_OF_ANKLE_PER_STATURE = 0.1636 / 1.8
CONTACT_BELOW_ANKLE_PER_STATURE = 0.039  # Winter's ankle height
#: Table A.2's weight band: mass (kg) and sagittal moment of inertia about its own CoM (I_Y, kg·m²)
WEIGHT_BAND = (1.719, 0.0043)
#: q (the chain's coordinates) = SIGNS · y: only the HAT angle's sense differs
SIGNS = np.array([1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0])


@dataclass(frozen=True)
class WalkerParameters:
    """Masses (kg), lengths (m) and sagittal inertias (kg·m², about the CoM) of the 7 bodies.

    ``hat_com_above_hip_m``/``hat_com_forward_m``: the 2-D HAT's CoM from the hip
    centre in the upright posture; ``limb``: thigh, shank and foot (one leg, the
    other equal); ``heel_behind_ankle_m``, ``mtp_ahead_of_ankle_m``,
    ``contact_below_ankle_m``: points A and B in the foot frame (foot ⟂ shank).
    """

    body_mass_kg: float
    stature_m: float
    hat_mass_kg: float
    hat_com_above_hip_m: float
    hat_com_forward_m: float
    hat_inertia_kgm2: float
    limb: LimbParameters
    heel_behind_ankle_m: float
    mtp_ahead_of_ankle_m: float
    contact_below_ankle_m: float
    notes: tuple[str, ...] = ()

    @classmethod
    def from_subject(cls, mass_kg: float, stature_m: float, sex: str = "male", *,
                     thigh_length_m: float | None = None, shank_length_m: float | None = None) -> WalkerParameters:
        """de Leva (1996) parameters of a subject; thigh and shank lengths measured where given."""
        limb = LimbParameters.from_anthropometry(mass_kg, stature_m, sex, thigh_length_m=thigh_length_m,
                                                 shank_length_m=shank_length_m)
        bodies = segment_parameters(mass_kg, stature_m, sex)
        pelvis, hat = bodies["pelvis"], bodies["hat"]
        # both 3-D bodies have their origin at the lumbar joint, the pelvis length above the hip centre (3.2.1)
        lumbar = np.array([0.0, 0.0, pelvis.length_m])
        parts = [(pelvis, lumbar + pelvis.com_m), (hat, lumbar + hat.com_m)]
        hat_mass = float(mass_kg) - 2 * (limb.thigh_mass_kg + limb.shank_mass_kg + limb.foot_mass_kg)
        part_mass = sum(body.mass_kg for body, _ in parts)
        scale = hat_mass / part_mass  # the legs of the limb and of the 3-D model are the same de Leva shares
        com = sum(body.mass_kg * scale * np.array([r[0], r[2]]) for body, r in parts) / hat_mass
        inertia = sum(scale * (body.inertia_kgm2[1, 1] + body.mass_kg * float(np.sum((np.array([r[0], r[2]])
                                                                                       - com) ** 2)))
                      for body, r in parts)
        H = float(stature_m)
        return cls(body_mass_kg=float(mass_kg), stature_m=H, hat_mass_kg=hat_mass,
                   hat_com_above_hip_m=float(com[1]), hat_com_forward_m=float(com[0]),
                   hat_inertia_kgm2=float(inertia), limb=limb,
                   heel_behind_ankle_m=HEEL_BEHIND_ANKLE_PER_STATURE * H,
                   mtp_ahead_of_ankle_m=MTP_AHEAD_OF_ANKLE_PER_STATURE * H,
                   contact_below_ankle_m=CONTACT_BELOW_ANKLE_PER_STATURE * H,
                   notes=limb.notes + ("2-D HAT: the 3-D model's pelvis (de Leva lower trunk) and HAT (head, upper "
                                       "and middle trunk, arms crossed) composed about the hip centre, I_yy",
                                       "heel and MTP points: gait2dc's 0.033·H and 0.091·H from the ankle, "
                                       "0.039·H below it (docs/model_constants.md §12)"))

    def with_foot_mass(self, mass_kg: float, at_m: tuple[float, float] | None = None) -> WalkerParameters:
        """The same subject with ``mass_kg`` added to each foot (5.3.2; docs/prediction.md, "Added foot mass").

        Default: a point mass at the foot's CoM, the foot's inertia unchanged. ``at_m`` = (forward of the
        ankle, below the ankle) in the foot frame, m: a band there with Table A.2's weight-band inertia
        scaled by mass (0.0043 kg·m² per 1.719 kg); the foot's CoM and inertia about it are recombined
        (parallel axes). The body mass grows by 2·``mass_kg``; the HAT keeps its mass.
        """
        if mass_kg == 0:
            return self
        limb = self.limb
        m0, m = limb.foot_mass_kg, float(mass_kg)
        com0 = np.array([limb.foot_com_forward_m, limb.foot_com_down_m])
        if at_m is None:
            com, inertia = com0, limb.foot_inertia_kgm2
        else:
            band = np.asarray(at_m, float)
            com = (m0 * com0 + m * band) / (m0 + m)
            inertia = (limb.foot_inertia_kgm2 + m0 * float(np.sum((com0 - com) ** 2))
                       + WEIGHT_BAND[1] * m / WEIGHT_BAND[0] + m * float(np.sum((band - com) ** 2)))
        where = ("at the foot's CoM" if at_m is None
                 else f"as a band at {at_m[0]:g} m forward, {at_m[1]:g} m below the ankle")
        limb = replace(limb, foot_mass_kg=m0 + m, foot_com_forward_m=float(com[0]), foot_com_down_m=float(com[1]),
                       foot_inertia_kgm2=float(inertia), body_mass_kg=limb.body_mass_kg + 2 * m)
        return replace(self, limb=limb, body_mass_kg=self.body_mass_kg + 2 * m,
                       notes=self.notes + (f"{m:g} kg added to each foot {where}",))

    @property
    def leg_length_m(self) -> float:
        """Hip centre to the sole of a flat foot, m: thigh + shank + the ankle's height (the L of Hof's
        dimensionless speed, ``speed_reference.py``)."""
        return self.limb.thigh_length_m + self.limb.shank_length_m + self.contact_below_ankle_m

    @classmethod
    def subject_1(cls) -> WalkerParameters:
        """The dissertation's subject 1 (73.0 kg, 1.792 m; thigh 0.475 m, shank 0.429 m)."""
        return cls.from_subject(**SUBJECT_1)


def _chain(p: WalkerParameters, gravity_m_s2: float) -> PlanarChain:
    """The chain in its own (counter-clockwise) angles: a floating HAT, the thighs absolute (sign −1)."""
    limb = p.limb
    segments = [Segment("hat", p.hat_mass_kg, p.hat_inertia_kgm2, 0.0, -p.hat_com_above_hip_m,
                        p.hat_com_forward_m, {"hip": (0.0, 0.0), "hat_com": (-p.hat_com_above_hip_m,
                                                                             p.hat_com_forward_m)})]
    joints = []
    for s in SIDES:
        segments += [
            Segment(f"thigh_{s}", limb.thigh_mass_kg, limb.thigh_inertia_kgm2, limb.thigh_length_m,
                    limb.thigh_com_m, points={f"knee_{s}": (limb.thigh_length_m, 0.0)}),
            Segment(f"shank_{s}", limb.shank_mass_kg, limb.shank_inertia_kgm2, limb.shank_length_m,
                    limb.shank_com_m, points={f"ankle_{s}": (limb.shank_length_m, 0.0)}),
            Segment(f"foot_{s}", limb.foot_mass_kg, limb.foot_inertia_kgm2, p.contact_below_ankle_m,
                    limb.foot_com_down_m, limb.foot_com_forward_m,
                    {f"heel_{s}": (p.contact_below_ankle_m, -p.heel_behind_ankle_m),
                     f"mtp_{s}": (p.contact_below_ankle_m, p.mtp_ahead_of_ankle_m)})]
        joints += [Joint(f"thigh_{s}", "hat", f"thigh_{s}", at=(0.0, 0.0), sign=-1.0, absolute=True),
                   Joint(f"knee_{s}", f"thigh_{s}", f"shank_{s}", sign=-1.0),
                   Joint(f"ankle_{s}", f"shank_{s}", f"foot_{s}", sign=-1.0)]
    return PlanarChain(segments, joints, base="floating", root="hat",
                       base_coordinates=("hip_x", "hip_z", "hat_angle"), gravity_m_s2=gravity_m_s2)


class WalkingModel:
    """The walking model's equations in the coordinates ``y`` (module docstring), as ``casadi.Function``s.

    - ``mass_matrix(y) → M`` (9 × 9); ``bias(y, yd) → k``; ``gravity(y) → g`` so that
      M ÿ + k = g + τ + Σ Q (5.1, without muscles and contacts);
    - ``points(y) → (x, z)`` per point in :attr:`point_names` (hip, HAT CoM, knees, ankles,
      heels A, MTPs B); ``point_jacobians(y) → ∂(x, z)/∂y`` per point;
    - ``centre_of_mass(y) → (x, z)``.
    """

    def __init__(self, params: WalkerParameters | None = None, *, gravity_m_s2: float = GRAVITY_M_S2):
        self.params = params if params is not None else WalkerParameters.subject_1()
        self.gravity_m_s2 = float(gravity_m_s2)
        self.chain = chain = _chain(self.params, gravity_m_s2)
        self.coordinates = COORDINATES
        self.total_mass_kg = chain.total_mass_kg
        self.point_names = chain.point_names
        sym = ca.SX.sym
        y, yd = sym("y", 9), sym("yd", 9)
        S = ca.DM(SIGNS)
        q, qd = S * y, S * yd
        Sm = ca.diag(S)
        F = ca.Function
        self.mass_matrix = F("mass_matrix", [y], [Sm @ chain.mass_matrix(q) @ Sm], ["y"], ["M"])
        self.bias = F("bias", [y, yd], [S * chain.bias(q, qd)], ["y", "yd"], ["k"])
        self.gravity = F("gravity", [y], [S * chain.gravity(q)], ["y"], ["g"])
        points = chain.points(q)
        points = points if isinstance(points, (list, tuple)) else [points]
        self.points = F("points", [y], list(points), ["y"], list(self.point_names))
        jacobians = chain.point_jacobians(q)
        jacobians = jacobians if isinstance(jacobians, (list, tuple)) else [jacobians]
        self.point_jacobians = F("point_jacobians", [y], [j @ Sm for j in jacobians], ["y"],
                                 [f"J_{n}" for n in self.point_names])
        self.centre_of_mass = F("centre_of_mass", [y], [chain.centre_of_mass(q)], ["y"], ["com"])
        at, force, moment = sym("at", 2), sym("force", 2), sym("moment")
        #: generalized force Q (9,) of a force (f_x, f_z) on a segment at the point ``at`` plus a free moment
        #: (positive counter-clockwise seen from the right, i.e. against the sense of the angles y)
        self.applied_force = {name: F(f"force_on_{name}", [y, at, force, moment],
                                      [S * chain.applied_force[name](q, at, force, moment)],
                                      ["y", "at", "force", "moment"], ["Q"]) for name in chain.segments}

    def point(self, name: str, y) -> np.ndarray:
        """(x, z) of one named point at ``y`` (9,), m."""
        return np.array(self.points(y)[self.point_names.index(name)]).ravel()
