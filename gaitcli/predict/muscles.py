"""The 16 muscles and the passive joint structures of the walking model (Diss. 5.2.2, A.1; 5.3.3).

Each leg carries the muscle stage's 8 Hill-type muscles (Table A.1) and its
Riener–Edrich passive moments with hip and knee damping, evaluated at that leg's
joint angles ψ = (hip flexion, knee flexion, ankle dorsiflexion) — the HAT-relative
hip angle, no upright-trunk assumption — which
:func:`gaitcli.kinematics.conventions.walker_joint_angles` gives from the model's
coordinates y. Generalized forces in y follow from the power balance:
``Q = (∂ψ/∂y)ᵀ τ_ψ``; for the muscles ``R(y) = −∂l_m/∂yᵀ`` (A.11), 9 × 16, right
muscles first, so that the muscles' contribution to (5.1) is ``R(y)·f_m``.

With bilateral transtibial prostheses (5.3.3; docs/prediction.md, "The prosthesis") soleus and tibialis
anterior are removed (:attr:`WalkerMuscles.present`), the gastrocnemius keeps its knee action with its
length at a neutral ankle, the Riener–Edrich ankle moment goes and their knee moment is evaluated at a
neutral ankle; the device's moment (5.59) acts on y6 and y9 in their own sense.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.muscles.hill import MuscleModel
from gaitcli.muscles.parameters import (
    MUSCLE_NAMES,
    JointParameters,
    MuscleParameters,
    table_a1,
)
from gaitcli.muscles.passive import JointModel
from gaitcli.predict.ankle_law import ProsthesisLaw
from gaitcli.predict.prosthesis import DEFAULT_LAW

#: (HAT, thigh, knee, ankle) indices of y per side
LEG_COORDINATES = {"r": (2, 3, 4, 5), "l": (2, 6, 7, 8)}
#: the muscles a transtibial amputation removes (5.3.3)
REMOVED_WITH_ANKLE = ("tibialis_anterior", "soleus")


def present_muscles(prosthetic: bool, names=MUSCLE_NAMES) -> np.ndarray:
    """(16,) which muscles the model has, right leg first (False: removed with a prosthetic ankle)."""
    removed = REMOVED_WITH_ANKLE if prosthetic else ()
    return np.array([name not in removed for _ in ("r", "l") for name in names])


class WalkerMuscles:
    """``casadi.Function``s of the walking model's muscles and passive structures in its coordinates y.

    - ``joint_angles(y) → (ψ_r, ψ_l)`` (3 each, rad);
    - ``lengths(y) → l_m`` (16, m) and ``velocities(y, yd) → v_m`` (16, m/s), right leg first;
    - ``moment_arms(y) → R`` (9 × 16): generalized force per newton of muscle force (A.11);
    - ``tissue(y, yd) → Q_t`` (9): Riener–Edrich moments and hip/knee damping as generalized forces;
    - ``device(y, yd, c) → Q_d`` (9): the prostheses' moments for coefficients ``c`` of their law (its
      ``COEFFICIENTS``, :meth:`~gaitcli.predict.ankle_law.ProsthesisLaw.nlp_moment_Nm`: (5.59) with τ_s's
      branches blended over ±ε(c) for the dissertation's law); zero without prostheses;
    - ``passive(y, yd) → Q_p = Q_t + Q_d`` with the given ``prosthesis``.

    ``prosthesis``: bilateral transtibial prostheses with this curve (module docstring); ``strength_scale``:
    every F_max times this (5.3.3: 1.5; muscle masses follow, (A.13): docs/prediction.md, "Stronger muscles").
    """

    def __init__(self, muscles: MuscleParameters | None = None, joints: JointParameters | None = None, *,
                 prosthesis: ProsthesisLaw | None = None, strength_scale: float = 1.0):
        params = muscles if muscles is not None else table_a1()
        if strength_scale != 1.0:
            params = params.with_options(max_isometric_force_N=strength_scale * params.max_isometric_force_N)
        self.prosthesis, self.strength_scale = prosthesis, float(strength_scale)
        joints = joints if joints is not None else JointParameters()
        if prosthesis is not None:
            joints = JointParameters(**{**joints.__dict__, "prosthetic_ankle": True})
        self.muscle = MuscleModel(params)
        self.joints = JointModel(joints)
        self.names = tuple(f"{name}_{s}" for s in ("r", "l") for name in self.muscle.names)
        #: (16,) which muscles the model has (False: removed with the ankle)
        self.present = present_muscles(prosthesis is not None, self.muscle.names)
        law = type(prosthesis) if prosthesis is not None else DEFAULT_LAW
        y, yd, c = ca.SX.sym("y", 9), ca.SX.sym("yd", 9), ca.SX.sym("c", len(law.COEFFICIENTS))
        psi = {s: ca.vertcat(*walker_joint_angles(*(y[i] for i in LEG_COORDINATES[s]))) for s in ("r", "l")}
        psi_rate = {s: ca.jtimes(psi[s], y, yd) for s in psi}
        # the muscles' paths (A.9): with a prosthesis, the ankle at neutral (Gas at the knee only)
        path = {s: ca.vertcat(psi[s][0], psi[s][1], 0) if prosthesis is not None else psi[s] for s in psi}
        lengths = ca.vertcat(*(self.muscle.length(path[s]) for s in ("r", "l")))
        tissue = sum(ca.jacobian(psi[s], y).T @ self.joints.total(psi[s], psi_rate[s]) for s in ("r", "l"))
        device = ca.SX.zeros(9)
        if prosthesis is not None:
            curve = law.from_values("symbolic", ca.vertsplit(c))
            for s in ("r", "l"):
                ankle = LEG_COORDINATES[s][3]
                device[ankle] = curve.nlp_moment_Nm(y[ankle], yd[ankle])  # cubic: τ_s,ε
        F = ca.Function
        self.joint_angles = F("joint_angles", [y], [psi["r"], psi["l"]], ["y"], ["psi_r", "psi_l"])
        self.lengths = F("lengths", [y], [lengths], ["y"], ["l_m"])
        self.velocities = F("velocities", [y, yd], [ca.jtimes(lengths, y, yd)], ["y", "yd"], ["v_m"])
        self.moment_arms = F("moment_arms", [y], [-ca.jacobian(lengths, y).T], ["y"], ["R"])
        self.tissue = F("tissue", [y, yd], [tissue], ["y", "yd"], ["Q_t"])
        self.device = F("device", [y, yd, c], [device], ["y", "yd", "c"], ["Q_d"])
        fixed = ca.DM(prosthesis.coefficients() if prosthesis is not None else np.zeros(len(law.COEFFICIENTS)))
        self.passive = F("passive", [y, yd], [tissue + self.device(y, yd, fixed)], ["y", "yd"], ["Q_p"])

    @property
    def prosthetic(self) -> bool:
        return self.prosthesis is not None

    @property
    def device_law(self) -> str:
        """The prostheses' law (``""`` without): what makes two prosthetic models' problems differ."""
        return self.prosthesis.law if self.prosthesis is not None else ""
