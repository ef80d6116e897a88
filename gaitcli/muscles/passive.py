"""Passive joint moments (Riener & Edrich 1999) and hip/knee damping (Stein et al. 1996) (4.5.1).

The moments are generalized forces of the limb model (hip flexion, knee
flexion, ankle dorsiflexion positive). Riener & Edrich's formulas (MODEL_CONSTANTS B)
take degrees with hip flexion, knee flexion and ankle *plantar*flexion positive
and return moments positive in the same sense as their angle.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from .evaluation import evaluate
from .parameters import JointParameters


def _riener_edrich(phi_h, phi_k, phi_a):
    """M_H, M_K, M_A in N·m from angles in degrees (MODEL_CONSTANTS B)."""
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
    ``damping(qd) → τ_d`` as generalized forces of the limb model; ``total(q, qd)``.
    """

    def __init__(self, params: JointParameters | None = None):
        self.params = p = params if params is not None else JointParameters()
        phi, q, qd = ca.SX.sym("phi", 3), ca.SX.sym("q", 3), ca.SX.sym("qd", 3)
        self.riener_edrich = ca.Function("riener_edrich", [phi], [ca.vertcat(*_riener_edrich(*ca.vertsplit(phi)))],
                                         ["phi_deg"], ["M_Nm"])
        deg = 180.0 / np.pi
        # hip flexion = thigh angle (trunk upright), knee flexion, plantarflexion = −dorsiflexion
        m_h, m_k, m_a = _riener_edrich(q[0] * deg, q[1] * deg, -q[2] * deg)
        scale = 1.0 if p.passive_moments else 0.0
        passive = scale * ca.vertcat(m_h, m_k, -m_a)
        damping = ca.vertcat(-p.hip_damping_Nms_per_rad * qd[0], -p.knee_damping_Nms_per_rad * qd[1], 0)
        self.passive = ca.Function("passive", [q], [passive], ["q"], ["tau_p"])
        self.damping = ca.Function("damping", [qd], [damping], ["qd"], ["tau_d"])
        self.total = ca.Function("total", [q, qd], [passive + damping], ["q", "qd"], ["tau"])

    def evaluate(self, name: str, *args):
        return evaluate(getattr(self, name), *args)
