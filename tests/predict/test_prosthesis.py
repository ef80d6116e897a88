"""Prosthetic ankle curves (gaitcli/predict/prosthesis.py, (5.58)–(5.59)) against known answers:
(5.58) evaluated by hand with Table A.7's and A.8's coefficients, independently of this code."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from gaitcli.predict.cubic_ankle import BLEND_ERROR_NM, BLEND_MAX_RAD, ProsthesisCurve
from gaitcli.predict.prosthesis import COMMERCIAL_FEET

ANGLES_RAD = (-0.3, -0.2, -0.1, 0.1, 0.2)
KNOWN_NM = {"sach": (603.2, 283.4, 80.5, -22.3, -48.2), "seattle": (246.6, 131.1, 50.0, -44.5, -243.2),
            "flex": (108.7, 67.1, 30.9, -26.4, -117.5)}
#: Table A.8's near-optimal feet at 1.00 m/s, weights a) and 1.33 m/s, weights b), with the same table's values
OPTIMAL = {"1.00 a": (ProsthesisCurve("opt", -17360, 1375, -100.0, -5231, 1630, 0.372),
                      (317.9, 127.0, 31.5, -13.6, -103.9)),
           "1.33 b": (ProsthesisCurve("opt", -16870, 1015, -171.0, -5189, -280, 0.051),
                      (166.2, 64.5, 19.5, -23.8, -128.6))}


@pytest.mark.parametrize("name", list(KNOWN_NM))
def test_commercial_feet_match_the_known_answers(name):
    np.testing.assert_allclose(COMMERCIAL_FEET[name].spring_moment_Nm(np.array(ANGLES_RAD)), KNOWN_NM[name],
                               atol=0.1)


@pytest.mark.parametrize("case", list(OPTIMAL))
def test_near_optimal_feet_match_the_known_answers(case):
    curve, known = OPTIMAL[case]
    np.testing.assert_allclose(curve.spring_moment_Nm(np.array(ANGLES_RAD)), known, atol=0.1)


@pytest.mark.parametrize("name", list(KNOWN_NM))
def test_zero_at_neutral_with_slope_c0_from_both_sides(name):
    curve = COMMERCIAL_FEET[name]
    h = 1e-6
    assert curve.spring_moment_Nm(0.0) == 0.0
    assert curve.spring_moment_Nm(h) / h == pytest.approx(curve.c0, rel=1e-3)
    assert curve.spring_moment_Nm(-h) / -h == pytest.approx(curve.c0, rel=1e-3)
    y = ca.SX.sym("y")
    slope = ca.Function("s", [y], [ca.jacobian(curve.spring_moment_Nm(y), y)])
    assert float(slope(1e-9)) == pytest.approx(curve.c0, rel=1e-6) and float(slope(-1e-9)) == pytest.approx(
        curve.c0, rel=1e-6)


@pytest.mark.parametrize("name", list(KNOWN_NM))
def test_the_nlps_blend_stays_within_its_bound_and_has_a_continuous_curvature(name):
    # max over u of u²·(1 − tanh u)/2 = 0.1207 and of u³·(1 − tanh u)/2 = 0.1606 (the bound of the docstring)
    curve = COMMERCIAL_FEET[name]
    eps = float(curve.branch_blend_rad())
    y = np.linspace(-0.5, 0.5, 100001)
    difference = np.abs(curve.spring_moment_Nm(y, eps) - curve.spring_moment_Nm(y))
    bound = 0.1207 * abs(curve.b_p - curve.b_n) * eps ** 2 + 0.1606 * abs(curve.a_p - curve.a_n) * eps ** 3
    assert difference.max() <= bound <= BLEND_ERROR_NM and difference[np.abs(y) >= 0.2].max() < 1e-6
    assert 0.01 < eps < BLEND_MAX_RAD
    np.testing.assert_allclose(curve.spring_moment_Nm(np.array(ANGLES_RAD), eps), KNOWN_NM[name], atol=0.1)
    s = ca.SX.sym("y")
    curvature = ca.Function("c", [s], [ca.hessian(curve.spring_moment_Nm(s, eps), s)[0]])
    assert float(curvature(1e-7)) == pytest.approx(float(curvature(-1e-7)), rel=1e-3, abs=1.0)
    exact = ca.Function("c", [s], [ca.hessian(curve.spring_moment_Nm(s), s)[0]])
    assert float(exact(1e-7)) == pytest.approx(2 * curve.b_p, rel=1e-3)  # (5.58) itself: the jump the blend removes
    assert float(exact(-1e-7)) == pytest.approx(2 * curve.b_n, rel=1e-3)


def test_the_blend_is_widest_where_the_branches_agree_and_smooth_in_the_coefficients():
    """ε = ε_max where the branches coincide (up to the 1 N·m/rad² of the smooth |·|), narrower the more their
    curvatures differ (SACH < Seattle ≈ Flex), and the same function of symbolic coefficients (the optimal
    device's) as of numbers."""
    same = ProsthesisCurve("same", -1000.0, 500.0, -200.0, -1000.0, 500.0, 1.0)
    assert float(same.branch_blend_rad()) == pytest.approx(BLEND_MAX_RAD, rel=1e-3)
    eps = {k: float(c.branch_blend_rad()) for k, c in COMMERCIAL_FEET.items()}
    assert eps["sach"] < eps["seattle"] < eps["flex"]
    c = ca.SX.sym("c", 6)
    symbolic = ca.Function("e", [c], [ProsthesisCurve("symbolic", *ca.vertsplit(c)).branch_blend_rad()])
    for curve in COMMERCIAL_FEET.values():
        assert float(symbolic(curve.coefficients())) == pytest.approx(float(curve.branch_blend_rad()), rel=1e-12)


def test_the_product_convention_gives_sach_a_plantarflexor_moment_at_dorsiflexion():
    """0.2 rad of dorsiflexion (y = −0.2): SACH resists with a 283.4 N·m plantarflexor moment (docs/prediction.md,
    "The ankle's sign")."""
    assert COMMERCIAL_FEET["sach"].plantarflexor_moment_Nm(0.2) == pytest.approx(283.4, abs=0.1)
    # dorsiflexion stiffness SACH > Seattle > Flex, as 5.3.3 says
    moments = [COMMERCIAL_FEET[k].plantarflexor_moment_Nm(0.2) for k in ("sach", "seattle", "flex")]
    assert moments == sorted(moments, reverse=True)


def test_damping_and_monotonicity():
    flex = COMMERCIAL_FEET["flex"]
    assert flex.moment_Nm(-0.1, 2.0) == pytest.approx(30.9 - 2.0, abs=0.1)  # (5.59), d = 1 N·m·s/rad
    limit = np.radians(28.6)
    assert flex.is_monotone(-limit, limit) and COMMERCIAL_FEET["seattle"].is_monotone(-limit, limit)
    # SACH's curve turns upward beyond +21.7° of plantarflexion (Table A.7's coefficients)
    assert not COMMERCIAL_FEET["sach"].is_monotone(-limit, limit)
    assert COMMERCIAL_FEET["sach"].is_monotone(-limit, np.radians(21.0))


RANGE = (float(np.radians(-25.0)), float(np.radians(10.0)))


def test_a_prosthesis_file_gives_its_curve():
    from gaitcli.predict.prosthesis import curve_from_mapping

    flex = COMMERCIAL_FEET["flex"]
    mapping = {"name": "my flex", "a_p": -17090, "b_p": 1889, "c0": -281.5, "a_n": 15.64, "b_n": 274.2,
               "d_prosth": 1.0}
    curve = curve_from_mapping(mapping, "foot.yaml", RANGE)
    assert curve.name == "my flex"
    np.testing.assert_array_equal(curve.coefficients(), flex.coefficients())


@pytest.mark.parametrize("change, field, words", [
    ({"c0": None}, "c0", "missing"),
    ({"b_n": "stiff"}, "b_n", "expected a finite number"),
    ({"b_n": float("nan")}, "b_n", "expected a finite number"),
    ({"d_prosth": -0.5}, "d_prosth", "damping ≥ 0"),
    ({"stiffness": 3}, "stiffness", "unknown key"),
    ({"b_n": -3000.0}, "prosthesis", "τ_s rises at"),  # rising in dorsiflexion: not a spring
])
def test_a_bad_prosthesis_file_is_refused_naming_the_field(change, field, words):
    from gaitcli.errors import InputError
    from gaitcli.predict.prosthesis import curve_from_mapping

    mapping = {"a_p": -17090, "b_p": 1889, "c0": -281.5, "a_n": 15.64, "b_n": 274.2, "d_prosth": 1.0}
    mapping.update(change)
    mapping = {k: v for k, v in mapping.items() if v is not None}
    with pytest.raises(InputError) as caught:
        curve_from_mapping(mapping, "foot.yaml", RANGE)
    assert caught.value.field == field and words in caught.value.problem


def test_sach_turns_beyond_the_declared_range_only():
    # Table A.7: SACH is monotone up to +21.7° of y and not beyond
    sach = COMMERCIAL_FEET["sach"]
    assert sach.is_monotone(np.radians(-28.6), np.radians(21.5))
    assert not sach.is_monotone(np.radians(-28.6), np.radians(22.5))
