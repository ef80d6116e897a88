"""Passive transtibial prosthetic ankles (Diss. 5.3.3, Appendix A.7; docs/prediction.md, "The prosthesis").

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

from dataclasses import dataclass

import casadi as ca
import numpy as np

from gaitcli.predict.splines import is_casadi

#: the curve's coefficients, Table A.7's names and order: the fields of :class:`ProsthesisCurve`, the optimal
#: device's design variables, a prosthesis file's keys, the ``prosthesis_<name>`` figures of summary.json and
#: study.csv
COEFFICIENTS = ("a_p", "b_p", "c0", "a_n", "b_n", "d_prosth")
#: the NLP's blend of the branches of (5.58): its largest departure from (5.58), N·m, and widest ε, rad
#: (module docstring; the moment equations themselves are met to PredictSettings.moment_tolerance_Nm = 2 N·m)
BLEND_ERROR_NM = 0.2
BLEND_MAX_RAD = 0.03


@dataclass(frozen=True)
class ProsthesisCurve:
    """The coefficients of (5.58)–(5.59), Table A.7: a_p, a_n N·m/rad³; b_p, b_n N·m/rad²; c0 N·m/rad; the
    damping d_prosth N·m·s/rad."""

    name: str
    a_p: float
    b_p: float
    c0: float
    a_n: float
    b_n: float
    d_prosth: float

    def coefficients(self) -> np.ndarray:
        """(a_p, b_p, c0, a_n, b_n, d_prosth) as an array (:data:`COEFFICIENTS`)."""
        return np.array([getattr(self, k) for k in COEFFICIENTS], float)

    def named(self, prefix: str = "") -> dict[str, float]:
        """{``prefix`` + name: value} of :data:`COEFFICIENTS`."""
        return {f"{prefix}{k}": float(getattr(self, k)) for k in COEFFICIENTS}

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

    def plantarflexor_moment_Nm(self, dorsiflexion_rad):
        """The spring's plantarflexor moment at a dorsiflexion angle in the product's convention
        (dorsiflexion positive, y = −δ; τ_s is positive plantarflexing): docs/prediction.md, "The ankle's sign"."""
        return self.spring_moment_Nm(-np.asarray(dorsiflexion_rad, float))

    def is_monotone(self, low_rad: float, high_rad: float, samples: int = 401) -> bool:
        """Whether τ_s decreases (dτ_s/dy ≤ 0) over [low, high] in y, checked at ``samples`` angles."""
        y = np.linspace(low_rad, high_rad, samples)
        slope = np.where(y > 0, 3 * self.a_p * y ** 2 + 2 * self.b_p * y, 3 * self.a_n * y ** 2 + 2 * self.b_n * y)
        return bool(np.all(slope + self.c0 <= 0.0))


#: Table A.7: the commercial feet fitted with (5.58), d_prosth = 1.0 N·m·s/rad
COMMERCIAL_FEET = {
    "sach": ProsthesisCurve("SACH", 1534.0, -640.0, -174.2, 914.8, 6396.0, 1.0),
    "seattle": ProsthesisCurve("Seattle", -34020.0, 2496.0, -354.3, -524.9, 1402.0, 1.0),
    "flex": ProsthesisCurve("Flex", -17090.0, 1889.0, -281.5, 15.64, 274.2, 1.0),
}

#: the ``--prosthesis`` choices besides a YAML file: none, a commercial foot, the optimal device (5.3.3)
CHOICES = ("none", *COMMERCIAL_FEET, "optimal")


def curve_from_mapping(mapping, path, monotone_range_rad: tuple[float, float]) -> ProsthesisCurve:
    """The curve of a prosthesis file's contents ({name?, a_p, b_p, c0, a_n, b_n, d_prosth}: N·m/rad³, /rad²,
    /rad, N·m·s/rad); an InputError naming ``path`` and the field when a coefficient is missing or not a finite
    number, d_prosth < 0, or τ_s does not decrease over ``monotone_range_rad`` (y, rad)."""
    from gaitcli.errors import InputError, shown

    if not isinstance(mapping, dict):
        raise InputError(path, "prosthesis", f"got {shown(mapping)} (expected a mapping of {', '.join(COEFFICIENTS)})")
    unknown = sorted(set(mapping) - set(COEFFICIENTS) - {"name"})
    if unknown:
        raise InputError(path, str(unknown[0]),
                         f"unknown key (expected {', '.join(COEFFICIENTS)} and an optional name)")
    values = []
    for key in COEFFICIENTS:
        value = mapping.get(key)
        if value is None:
            raise InputError(path, key, "missing (expected a number: the curve of (5.58)–(5.59), Table A.7's units)")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise InputError(path, key, f"got {shown(value)} (expected a finite number)")
        values.append(float(value))
    if values[5] < 0:
        raise InputError(path, "d_prosth", f"got {values[5]:g} (expected a damping ≥ 0 N·m·s/rad)")
    curve = ProsthesisCurve(str(mapping.get("name", "file")), *values)
    low, high = monotone_range_rad
    if not curve.is_monotone(low, high):
        y = np.linspace(low, high, 401)
        slope = np.gradient(curve.spring_moment_Nm(y), y)
        worst = float(np.degrees(y[int(np.argmax(slope))]))
        raise InputError(path, "prosthesis", f"τ_s rises at y = {worst:.1f}° (expected a spring moment that "
                                             f"decreases over {np.degrees(low):g}° … {np.degrees(high):g}°, 5.3.3)")
    return curve


def curve_for(name: str) -> ProsthesisCurve | None:
    """The commercial foot ``name`` (Table A.7), None for "none" and "optimal"."""
    return COMMERCIAL_FEET.get(name)
