"""The eight contact phases of a walking cycle and their ground reactions (Diss. 5.2.3, 5.2.8).

Phases (Fig. 5.3, 5.2.3): 1 right heel strike → right foot flat,
2 → left toe off, 3 → right heel off, 4 → left heel strike, and 5–8 the same
with the sides exchanged. In each phase the contact points in touch with the
floor are pinned (5.6–5.9): heel A_x, A_z, MTP B_x, B_z at the places the step
lengths L_r, L_l fix, with δ the heel-to-MTP distance and x0 the left MTP's
place in phase 1:

    ph  c_ph = 0                                                       rows
    1   B_l,x − x0;  B_l,z;  A_r,x − (x0 + L_r − δ);  A_r,z               4
    2   phase 1 and B_r,z (right foot flat)                              5
    3   A_r,x − (x0 + L_r − δ);  A_r,z;  B_r,z                            3
    4   B_r,x − (x0 + L_r);  B_r,z                                        2
    5   B_r,x − (x0 + L_r);  B_r,z;  A_l,x − (x0 + L_r + L_l − δ);  A_l,z 4
    6   phase 5 and B_l,z                                                5
    7   A_l,x − (x0 + L_r + L_l − δ);  A_l,z;  B_l,z                      3
    8   B_l,x − (x0 + L_r + L_l);  B_l,z                                  2

The reactions λ_ph are the point-force components of those rows (the ground
on the foot, N). Where a foot stands on B alone (right in 4, 5; left in 8, 1)
an MTP moment m_B (N·m, clockwise-positive like the model's angles; bounded
to −10 … 0 N·m by 5.2.2) is one more reaction: without it phases 4 and 8 leave
the whole body's moment balance about the stance MTP point unconstrained
(2 + 6 < 9 unknowns; docs/prediction.md, "MTP moment").

Ground reactions by the pseudoinverse (5.30): with ``G = [C_phᵀ, m_B column]``
and ``rhs = M ÿ + k − q_r − R f_m``, ``λ* = G⁺ rhs`` and the residual (5.31)
``e = rhs − G λ*``; written with CasADi operations so that it runs on symbols
(the NLP) and on numbers alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.predict.model import WalkingModel

PHASES = (1, 2, 3, 4, 5, 6, 7, 8)
#: the places of the pinned x coordinates, in terms of x0, L_r, L_l and δ (the heel-to-MTP distance)
TARGETS = {"x0": (1, 0, 0, 0), "right_heel": (1, 1, 0, -1), "right_mtp": (1, 1, 0, 0),
           "left_heel": (1, 1, 1, -1), "left_mtp": (1, 1, 1, 0)}


@dataclass(frozen=True)
class Phase:
    """One contact phase: its constraint rows (point, axis, target of an x row) and the side whose foot
    stands on its MTP point alone (and so has an MTP moment reaction), if any."""

    number: int
    rows: tuple[tuple[str, str, str | None], ...]
    mtp_moment_side: str | None = None

    def points(self) -> tuple[str, ...]:
        """The contact points in touch with the floor (in row order, once each)."""
        return tuple(dict.fromkeys(point for point, _, _ in self.rows))


def _pin(point: str, target: str) -> tuple[tuple[str, str, str | None], ...]:
    return ((point, "x", target), (point, "z", None))


PHASE_TABLE = (
    Phase(1, _pin("mtp_l", "x0") + _pin("heel_r", "right_heel"), mtp_moment_side="l"),
    Phase(2, _pin("mtp_l", "x0") + _pin("heel_r", "right_heel") + (("mtp_r", "z", None),)),
    Phase(3, _pin("heel_r", "right_heel") + (("mtp_r", "z", None),)),
    Phase(4, _pin("mtp_r", "right_mtp"), mtp_moment_side="r"),
    Phase(5, _pin("mtp_r", "right_mtp") + _pin("heel_l", "left_heel"), mtp_moment_side="r"),
    Phase(6, _pin("mtp_r", "right_mtp") + _pin("heel_l", "left_heel") + (("mtp_l", "z", None),)),
    Phase(7, _pin("heel_l", "left_heel") + (("mtp_l", "z", None),)),
    Phase(8, _pin("mtp_l", "left_mtp"), mtp_moment_side="l"),
)

#: joint moments (hip, knee, ankle per side), each positive in the sense of its joint angle (hip: y4 − y3)
JOINT_MOMENTS = ("hip_r", "knee_r", "ankle_r", "hip_l", "knee_l", "ankle_l")


def joint_moment_map() -> np.ndarray:
    """B (9 × 6): generalized forces of the six joint moments (power τ·ω_relative; 5.1's R = B·A)."""
    B = np.zeros((9, 6))
    for k, (thigh, knee, ankle) in enumerate(((3, 4, 5), (6, 7, 8))):
        B[thigh, 3 * k], B[2, 3 * k] = 1.0, -1.0  # hip angle y_thigh − y3
        B[knee, 3 * k + 1] = 1.0
        B[ankle, 3 * k + 2] = 1.0
    return B


def foot_rotation(side: str) -> np.ndarray:
    """∂φ_foot/∂y (9,): the foot's clockwise angle is thigh + knee + ankle (the generalized force of a moment)."""
    row = np.zeros(9)
    row[[3, 4, 5] if side == "r" else [6, 7, 8]] = 1.0
    return row


class ContactModel:
    """The phases' constraints and reaction matrices for one walking model, as ``casadi.Function``s.

    ``constraint[ph](y, L_r, L_l, x0) → c`` (rows of the phase, m);
    ``jacobian[ph](y) → C = ∂c/∂y`` (rows × 9); ``reaction_matrix[ph](y) → G`` (9 × n_λ):
    ``C_phᵀ`` and, where the phase has one, the MTP moment's column. ``heel_to_mtp_m`` = δ.
    """

    def __init__(self, model: WalkingModel):
        self.model = model
        p = model.params
        self.heel_to_mtp_m = p.heel_behind_ankle_m + p.mtp_ahead_of_ankle_m
        y = ca.SX.sym("y", 9)
        L_r, L_l, x0 = ca.SX.sym("L_r"), ca.SX.sym("L_l"), ca.SX.sym("x0")
        places = ca.vertcat(x0, L_r, L_l, self.heel_to_mtp_m)
        points = dict(zip(model.point_names, model.points(y)))
        self.constraint, self.jacobian, self.reaction_matrix, self.reaction_names = {}, {}, {}, {}
        for phase in PHASE_TABLE:
            rows, names = [], []
            for point, axis, target in phase.rows:
                if axis == "x":
                    rows.append(points[point][0] - ca.dot(ca.DM(TARGETS[target]), places))
                else:
                    rows.append(points[point][1])
                names.append(f"{point}_f{axis}_N")
            c = ca.vertcat(*rows)
            C = ca.jacobian(c, y)
            G = C.T
            if phase.mtp_moment_side is not None:
                G = ca.horzcat(G, ca.DM(foot_rotation(phase.mtp_moment_side)))
                names.append(f"mtp_{phase.mtp_moment_side}_moment_Nm")
            n = phase.number
            self.constraint[n] = ca.Function(f"c{n}", [y, L_r, L_l, x0], [c], ["y", "L_r", "L_l", "x0"], ["c"])
            self.jacobian[n] = ca.Function(f"C{n}", [y], [C], ["y"], ["C"])
            self.reaction_matrix[n] = ca.Function(f"G{n}", [y], [G], ["y"], ["G"])
            self.reaction_names[n] = tuple(names)

    @staticmethod
    def phase(number: int) -> Phase:
        return PHASE_TABLE[number - 1]


def ground_reactions(G, rhs):
    """λ* = G⁺·rhs (5.30) and the residual e = rhs − G·λ* (5.31), for G of full column rank.

    Works on numpy arrays and on CasADi expressions (the normal equations GᵀG λ = Gᵀ rhs).
    """
    if isinstance(G, np.ndarray) and isinstance(rhs, np.ndarray):
        lam = np.linalg.lstsq(G, rhs, rcond=None)[0]
        return lam, rhs - G @ lam
    lam = ca.solve(G.T @ G, G.T @ rhs)
    return lam, rhs - G @ lam
