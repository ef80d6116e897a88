"""The dissertation's prosthetic ankle law (Diss. 5.3.3, Appendix A.7; docs/prediction.md, "The prosthesis"): the
``cubic`` entry of :data:`gaitcli.predict.prosthesis.LAWS`.

The ankle moment of a prosthetic foot is a function of the model's ankle angle y (y6 or y9, rad; y < 0 is
dorsiflexion: docs/prediction.md, "The ankle's sign") and its rate:

    τ_s(y) = a_p y³ + b_p y² + c0 y   (y > 0),    a_n y³ + b_n y² + c0 y   (y ≤ 0)        (5.58)
    τ_prosth = τ_s(y) − d_prosth ẏ                                                    (5.59)

in N·m, positive in the sense of y (plantarflexing), so a restoring spring decreases with y (c0 < 0). τ_s(0) = 0
and its slope is c0 from both sides. The three commercial feet are Table A.7's fits of Klute et al.'s curves.

Deviation in the NLP (:meth:`ProsthesisCurve.branch_blend_rad`): the two branches meet at y = 0 with equal
value and slope but not curvature (SACH: 2·b_p = −1280, 2·b_n = 12792 N·m/rad²), so the exact Hessian jumps
there, and IPOPT crawls wherever an instant's ankle rests at neutral (a prosthetic ankle does through swing;
docs/decisions.md, "The prosthesis's branches blended"). The NLP therefore uses σ(y) = ½(1 + tanh(y/ε)):

    τ_s,ε(y) = σ(y)·plantar(y) + (1 − σ(y))·dorsal(y)

which differs from (5.58) by at most B ε² + A ε³, B = 0.121·|b_p − b_n|, A = 0.161·|a_p − a_n|, and (for the
three feet) by less than 10⁻⁶ N·m beyond |y| = 0.2 rad. ε is as wide as an error budget of :data:`BLEND_ERROR_NM`
allows, at most :data:`BLEND_MAX_RAD`: ε = ε_max / √(1 + (B + A ε_max) ε_max² / δ), which keeps
B ε² + A ε³ ≤ δ. Seattle's and Flex's branches differ less in curvature than SACH's, so they get a wider blend
(ε = 0.0197, 0.0200 rad; SACH 0.0136): one narrow ε for all feet converges slowly. The free device of the
optimal prosthesis gets the same ε as a smooth function of its coefficients. Every output (prosthesis.csv,
the plots, the tables) uses (5.58) itself.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np

from gaitcli.predict.ankle_law import ProsthesisLaw
from gaitcli.predict.splines import is_casadi

#: the NLP's blend of the branches of (5.58): its largest departure from (5.58), N·m, and widest ε, rad
#: (module docstring; the moment equations themselves are met to PredictSettings.moment_tolerance_Nm = 2 N·m)
BLEND_ERROR_NM = 0.2
BLEND_MAX_RAD = 0.03


@dataclasses.dataclass(frozen=True)
class ProsthesisCurve(ProsthesisLaw):
    """The coefficients of (5.58)–(5.59), Table A.7: a_p, a_n N·m/rad³; b_p, b_n N·m/rad²; c0 N·m/rad; the
    damping d_prosth N·m·s/rad."""

    a_p: float
    b_p: float
    c0: float
    a_n: float
    b_n: float
    d_prosth: float

    law = "cubic"
    #: Table A.7's names and order
    COEFFICIENTS = ("a_p", "b_p", "c0", "a_n", "b_n", "d_prosth")
    SCALE = np.array([1e4, 1e3, 1e2, 1e3, 1e3, 1.0])
    #: the optimal prosthesis's box: it contains Table A.7's feet and Table A.8's optima; c0 ≤ 0 (a restoring
    #: spring), 0 ≤ d_prosth ≤ 2 N·m·s/rad (docs/prediction.md, "The prosthesis")
    BOUNDS = (np.array([-6e4, -1.2e4, -500.0, -1e4, -2e3, 0.0]), np.array([6e4, 1.2e4, 0.0, 1e4, 8e3, 2.0]))
    #: c0's scale
    SLOPE_SCALE = 1e2

    def branch_blend_rad(self):
        """ε of the NLP's τ_s,ε for these coefficients (rad; numpy or CasADi coefficients; module docstring)."""
        lib = ca if is_casadi(self.b_p) or is_casadi(self.a_p) else np
        curvature = 0.1207 * lib.sqrt((self.b_p - self.b_n) ** 2 + 1.0)
        cubic = 0.1606 * lib.sqrt((self.a_p - self.a_n) ** 2 + 1.0)
        return BLEND_MAX_RAD / lib.sqrt(1.0 + (curvature + cubic * BLEND_MAX_RAD) * BLEND_MAX_RAD ** 2 / BLEND_ERROR_NM)

    def spring_moment_Nm(self, y, blend_rad: float = 0.0):
        """τ_s(y) (5.58) at ankle angles ``y`` (rad; numpy or CasADi); with ``blend_rad`` = ε > 0 the branches
        blended by ½(1 + tanh(y/ε)) (the NLP's τ_s,ε, module docstring)."""
        plantar = (self.a_p * y + self.b_p) * y * y + self.c0 * y
        dorsal = (self.a_n * y + self.b_n) * y * y + self.c0 * y
        lib = ca if is_casadi(y) else np
        if is_casadi(blend_rad) or blend_rad > 0:
            share = 0.5 * (1 + lib.tanh(y / blend_rad))
            return share * plantar + (1 - share) * dorsal
        if lib is ca:
            return ca.if_else(y > 0, plantar, dorsal)
        return np.where(np.asarray(y) > 0, plantar, dorsal)

    def moment_Nm(self, y, y_rate, blend_rad: float = 0.0):
        """τ_prosth = τ_s(y) − d_prosth·ẏ (5.59), N·m (``blend_rad``: as :meth:`spring_moment_Nm`)."""
        return self.spring_moment_Nm(y, blend_rad) - self.d_prosth * y_rate

    def nlp_moment_Nm(self, y, y_rate):
        """τ_prosth with τ_s,ε: the branches blended over :meth:`branch_blend_rad` (module docstring)."""
        return self.moment_Nm(y, y_rate, self.branch_blend_rad())

    def slope_Nm_per_rad(self, y):
        """dτ_s/dy = 3·a·y² + 2·b·y + c0 of the branch y lies on (numpy arrays, or numbers with numeric or
        CasADi coefficients)."""
        if np.ndim(y) == 0 and not is_casadi(y):
            a3, a2 = (self.a_p, self.b_p) if y > 0 else (self.a_n, self.b_n)
            return 3 * a3 * y ** 2 + 2 * a2 * y + self.c0
        y = np.asarray(y, float)
        return np.where(y > 0, 3 * self.a_p * y ** 2 + 2 * self.b_p * y,
                        3 * self.a_n * y ** 2 + 2 * self.b_n * y) + self.c0

    def checked(self, path) -> ProsthesisCurve:
        """A file's curve: d_prosth ≥ 0 (an InputError naming ``path`` and d_prosth otherwise)."""
        from gaitcli.errors import InputError

        if self.d_prosth < 0:
            raise InputError(path, "d_prosth", f"got {self.d_prosth:g} (expected a damping ≥ 0 N·m·s/rad)")
        return self
