"""Passive transtibial prosthetic ankles (Diss. 5.3.3, Appendix A.7): the laws a prediction may use, the
commercial feet of Table A.7 and prosthesis files.

A law (:class:`gaitcli.predict.ankle_law.ProsthesisLaw`) is one module with its dataclass and one entry of
:data:`LAWS`; the dissertation's is ``cubic``, (5.58)–(5.59) (:mod:`gaitcli.predict.cubic_ankle`), the law of
the commercial feet and of the optimal prosthesis. A prosthesis file (``--prosthesis FILE.yaml``) names its law
(``law:``, default ``cubic``), an optional ``name`` and the law's coefficients.
"""

from __future__ import annotations

import numpy as np

from gaitcli.predict.ankle_law import ProsthesisLaw
from gaitcli.predict.cubic_ankle import ProsthesisCurve

#: the prosthetic ankle laws by name (a prosthesis file's ``law:``)
LAWS: dict[str, type[ProsthesisLaw]] = {"cubic": ProsthesisCurve}
#: the law of the optimal prosthesis (5.3.3) and of a file that names none
DEFAULT_LAW = ProsthesisCurve
#: the dissertation's coefficients (Table A.7's names)
COEFFICIENTS = ProsthesisCurve.COEFFICIENTS

#: Table A.7: the commercial feet fitted with (5.58), d_prosth = 1.0 N·m·s/rad
COMMERCIAL_FEET = {
    "sach": ProsthesisCurve("SACH", 1534.0, -640.0, -174.2, 914.8, 6396.0, 1.0),
    "seattle": ProsthesisCurve("Seattle", -34020.0, 2496.0, -354.3, -524.9, 1402.0, 1.0),
    "flex": ProsthesisCurve("Flex", -17090.0, 1889.0, -281.5, 15.64, 274.2, 1.0),
}

#: the ``--prosthesis`` choices besides a YAML file: none, a commercial foot, the optimal device (5.3.3)
CHOICES = ("none", *COMMERCIAL_FEET, "optimal")


def curve_from_mapping(mapping, path, monotone_range_rad: tuple[float, float]) -> ProsthesisLaw:
    """The device of a prosthesis file's contents ({law?, name?, <the law's coefficients>}; Table A.7's units
    for ``cubic``); an InputError naming ``path`` and the field when the law is unknown, a coefficient is
    missing or not a finite number, the law's own checks fail (``cubic``: d_prosth ≥ 0), or τ_s does not
    decrease over ``monotone_range_rad`` (y, rad)."""
    from gaitcli.errors import InputError, shown

    law = DEFAULT_LAW
    if isinstance(mapping, dict) and "law" in mapping:
        if mapping["law"] not in LAWS:
            raise InputError(path, "law", f"got {shown(mapping['law'])} (expected one of {', '.join(LAWS)})")
        law = LAWS[mapping["law"]]
    keys = ", ".join(law.COEFFICIENTS)
    if not isinstance(mapping, dict):
        raise InputError(path, "prosthesis", f"got {shown(mapping)} (expected a mapping of {keys})")
    unknown = sorted(set(mapping) - set(law.COEFFICIENTS) - {"name", "law"})
    if unknown:
        raise InputError(path, str(unknown[0]), f"unknown key (expected {keys}, an optional name and law)")
    values = []
    for key in law.COEFFICIENTS:
        value = mapping.get(key)
        if value is None:
            raise InputError(path, key, f"missing (expected a number: a coefficient of the {law.law} law)")
        if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 1e300:
            raise InputError(path, key, f"got a {len(str(abs(value)))}-digit integer (expected a finite number "
                                        "of a float's range)")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise InputError(path, key, f"got {shown(value)} (expected a finite number)")
        values.append(float(value))
    curve = law.from_values(str(mapping.get("name", "file")), values).checked(path)
    low, high = monotone_range_rad
    if not curve.is_monotone(low, high):
        y = np.linspace(low, high, 401)
        worst = float(np.degrees(y[int(np.argmax(curve.slope_Nm_per_rad(y)))]))
        raise InputError(path, "prosthesis", f"τ_s rises at y = {worst:.1f}° (expected a spring moment that "
                                             f"decreases over {np.degrees(low):g}° … {np.degrees(high):g}°, 5.3.3)")
    return curve


def curve_for(name: str) -> ProsthesisLaw | None:
    """The commercial foot ``name`` (Table A.7), None for "none" and "optimal"."""
    return COMMERCIAL_FEET.get(name)
