"""The 16 muscles and the passive joint structures of the walking model (Diss. 5.2.2, A.1).

Each leg carries the muscle stage's 8 Hill-type muscles (Table A.1) and its
Riener–Edrich passive moments with hip and knee damping, evaluated at that leg's
joint angles ψ = (hip flexion, knee flexion, ankle dorsiflexion) — the HAT-relative
hip angle, no upright-trunk assumption — which
:func:`gaitcli.kinematics.conventions.walker_joint_angles` gives from the model's
coordinates y. Generalized forces in y follow from the power balance:
``Q = (∂ψ/∂y)ᵀ τ_ψ``; for the muscles ``R(y) = −∂l_m/∂yᵀ`` (A.11), 9 × 16, right
muscles first, so that the muscles' contribution to (5.1) is ``R(y)·f_m``.
"""

from __future__ import annotations

import casadi as ca

from gaitcli.kinematics.conventions import walker_joint_angles
from gaitcli.muscles.hill import MuscleModel
from gaitcli.muscles.parameters import JointParameters, MuscleParameters
from gaitcli.muscles.passive import JointModel

#: (HAT, thigh, knee, ankle) indices of y per side
LEG_COORDINATES = {"r": (2, 3, 4, 5), "l": (2, 6, 7, 8)}


class WalkerMuscles:
    """``casadi.Function``s of the walking model's muscles and passive structures in its coordinates y.

    - ``joint_angles(y) → (ψ_r, ψ_l)`` (3 each, rad);
    - ``lengths(y) → l_m`` (16, m) and ``velocities(y, yd) → v_m`` (16, m/s), right leg first;
    - ``moment_arms(y) → R`` (9 × 16): generalized force per newton of muscle force (A.11);
    - ``passive(y, yd) → Q_p`` (9): Riener–Edrich moments and hip/knee damping as generalized forces.
    """

    def __init__(self, muscles: MuscleParameters | None = None, joints: JointParameters | None = None):
        self.muscle = MuscleModel(muscles)
        self.joints = JointModel(joints)
        self.names = tuple(f"{name}_{s}" for s in ("r", "l") for name in self.muscle.names)
        y, yd = ca.SX.sym("y", 9), ca.SX.sym("yd", 9)
        psi = {s: ca.vertcat(*walker_joint_angles(*(y[i] for i in LEG_COORDINATES[s]))) for s in ("r", "l")}
        psi_rate = {s: ca.jtimes(psi[s], y, yd) for s in psi}
        lengths = ca.vertcat(*(self.muscle.length(psi[s]) for s in ("r", "l")))
        passive = sum(ca.jacobian(psi[s], y).T @ self.joints.total(psi[s], psi_rate[s]) for s in ("r", "l"))
        F = ca.Function
        self.joint_angles = F("joint_angles", [y], [psi["r"], psi["l"]], ["y"], ["psi_r", "psi_l"])
        self.lengths = F("lengths", [y], [lengths], ["y"], ["l_m"])
        self.velocities = F("velocities", [y, yd], [ca.jtimes(lengths, y, yd)], ["y", "yd"], ["v_m"])
        self.moment_arms = F("moment_arms", [y], [-ca.jacobian(lengths, y).T], ["y"], ["R"])
        self.passive = F("passive", [y, yd], [passive], ["y", "yd"], ["Q_p"])
