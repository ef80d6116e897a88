"""Passive joint moments (Riener & Edrich 1999) and hip/knee damping (Stein et al. 1996) (4.5.1).

The model takes the sagittal joint angles ψ = (hip flexion relative to the
pelvis/HAT, knee flexion, ankle dorsiflexion) in rad and their rates, and returns
joint moments in the same senses (for the limb of ``limb.py``, upright trunk,
ψ = q and these are its generalized forces). Riener & Edrich's formulas
(docs/model_constants.md §10) take degrees with hip flexion, knee flexion and ankle
*plantar*flexion positive and return moments positive in the same sense as
their angle; the conversions are those of :mod:`gaitcli.kinematics.conventions`.
"""

from __future__ import annotations

import casadi as ca

from gaitcli.kinematics.conventions import riener_edrich_angles, riener_edrich_moments

from .evaluation import evaluate
from .parameters import JointParameters


def _riener_edrich(phi_h, phi_k, phi_a):
    """M_H, M_K, M_A in N·m from angles in degrees (docs/model_constants.md §10)."""
    m_h = (ca.exp(1.4655 - 0.0034 * phi_k - 0.0750 * phi_h)
           - ca.exp(1.3403 - 0.0226 * phi_k + 0.0305 * phi_h) + 8.072)
    m_k = (ca.exp(1.800 - 0.0460 * phi_a - 0.0352 * phi_k + 0.0217 * phi_h)
           - ca.exp(-3.971 - 0.0004 * phi_a + 0.0495 * phi_k - 0.0128 * phi_h)
           - 4.820 + ca.exp(2.220 - 0.150 * phi_k))
    m_a = (ca.exp(2.1016 - 0.0843 * phi_a - 0.0176 * phi_k)
           - ca.exp(-7.9763 + 0.1949 * phi_a + 0.0008 * phi_k) - 1.792)
    return m_h, m_k, m_a


class JointModel:
    """Compiled passive joint moments.

    Functions: ``riener_edrich(phi_deg) → M`` (their own angles/signs, for
    checks against published values); ``passive(q) → τ_p`` and
    ``damping(qd) → τ_d`` as joint moments from the joint angles ψ (``q``) and
    their rates (``qd``); ``total(q, qd)``.
    """

    def __init__(self, params: JointParameters | None = None):
        self.params = p = params if params is not None else JointParameters()
        phi, q, qd = ca.SX.sym("phi", 3), ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
        self.riener_edrich = ca.Function("riener_edrich", [phi], [ca.vertcat(*_riener_edrich(*ca.vertsplit(phi)))],
                                         ["phi_deg"], ["M_Nm"])
        phi_h, phi_k, phi_a = riener_edrich_angles(q[0], q[1], q[2])
        m_h, m_k, m_a = _riener_edrich(phi_h, phi_k, 0.0 if p.prosthetic_ankle else phi_a)
        moments = riener_edrich_moments(m_h, m_k, 0.0 if p.prosthetic_ankle else m_a)
        scale = 1.0 if p.passive_moments else 0.0
        passive = scale * ca.vertcat(*moments)
        damping = ca.vertcat(-p.hip_damping_Nms_per_rad * qd[0], -p.knee_damping_Nms_per_rad * qd[1], 0)
        self.passive = ca.Function("passive", [q], [passive], ["q"], ["tau_p"])
        self.damping = ca.Function("damping", [qd], [damping], ["qd"], ["tau_d"])
        self.total = ca.Function("total", [q, qd], [passive + damping], ["q", "qd"], ["tau"])

    def evaluate(self, name: str, *args):
        return evaluate(getattr(self, name), *args)
