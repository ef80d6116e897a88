"""de Leva segment parameters and the HAT/pelvis split of Table A.4."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.kinematics.anthropometry import DE_LEVA, rotate_segment, segment_parameters
from gaitcli.kinematics.model import BODIES

SUBJECT1 = dict(mass_kg=73.0, stature_m=1.792)  # Tables A.4-A.5


@pytest.mark.parametrize("sex", ["male", "female"])
def test_de_leva_fractions_sum_to_whole_body(sex):
    t = DE_LEVA[sex]
    whole = t["head"].mass_pct + t["trunk"].mass_pct + 2 * sum(
        t[k].mass_pct for k in ("upper_arm", "forearm", "hand", "thigh", "shank", "foot"))
    assert whole == pytest.approx(100.0, abs=0.02)  # table values are rounded to 0.01 %
    parts = sum(t[k].mass_pct for k in ("upper_trunk", "middle_trunk", "lower_trunk"))
    assert parts == pytest.approx(t["trunk"].mass_pct, abs=1e-9)
    lengths = sum(t[k].length_mm for k in ("upper_trunk", "middle_trunk", "lower_trunk"))
    assert lengths == pytest.approx(t["trunk"].length_mm, abs=1e-9)
    segs = segment_parameters(70.0, 1.7, sex)
    assert list(segs) == list(BODIES)
    assert sum(s.mass_kg for s in segs.values()) == pytest.approx(70.0, abs=1e-12)


def test_pelvis_reproduces_table_a4():
    pelvis = segment_parameters(**SUBJECT1)["pelvis"]
    assert pelvis.mass_kg == pytest.approx(8.15, abs=0.005)
    assert -pelvis.com_m[2] == pytest.approx(0.092, abs=0.0005)  # c1: lumbar joint to CoM
    assert pelvis.length_m + pelvis.com_m[2] == pytest.approx(0.058, abs=0.0005)  # d2: CoM to hips
    np.testing.assert_allclose(np.diag(pelvis.inertia_kgm2), [0.0694, 0.0557, 0.0632], atol=0.00006)


@pytest.mark.parametrize("mass, stature, hat_mass, c2, inertia", [
    (73.0, 1.792, 35.85, 0.269, (1.6061, 1.1903, 0.5175)),
    (74.6, 1.785, 36.64, 0.268, (1.6585, 1.2064, 0.5539)),
])
def test_hat_reproduces_table_a4(mass, stature, hat_mass, c2, inertia):
    hat = segment_parameters(mass, stature)["hat"]
    assert hat.mass_kg == pytest.approx(hat_mass, abs=0.005)
    assert hat.com_m[2] == pytest.approx(c2, abs=0.0005)
    # the dissertation's arm layout is not printed; ours matches its HAT inertias to 6 %
    np.testing.assert_allclose(np.diag(hat.inertia_kgm2), inertia, rtol=0.06)
    assert np.allclose(hat.inertia_kgm2, np.diag(np.diag(hat.inertia_kgm2)))  # symmetric layout: principal


def test_limbs_follow_de_leva_with_measured_lengths():
    segs = segment_parameters(**SUBJECT1, thigh_length_m=0.475, shank_length_m=(0.429, 0.431))
    thigh, shank_r, shank_l, foot = segs["thigh_r"], segs["shank_r"], segs["shank_l"], segs["foot_r"]
    assert thigh.mass_kg == pytest.approx(10.34, abs=0.005)
    assert -thigh.com_m[2] == pytest.approx(0.195, abs=0.0005)  # Table A.5 c3
    assert -shank_r.com_m[2] == pytest.approx(0.188, abs=0.0006)  # Table A.5 c4 (KJC->AJC row), 0.18855
    assert shank_l.length_m == 0.431
    m, L = 0.1416 * 73.0, 0.475
    np.testing.assert_allclose(np.diag(thigh.inertia_kgm2), m * (np.array([0.329, 0.329, 0.149]) * L) ** 2)
    assert foot.mass_kg == pytest.approx(1.00, abs=0.005)
    assert foot.com_m[0] == pytest.approx(0.117, abs=0.0005)  # Table A.5 h5, from the heel
    np.testing.assert_allclose(np.diag(foot.inertia_kgm2), [0.0011, 0.0047, 0.0042], atol=0.00006)


def test_bad_subject_values_are_input_errors():
    with pytest.raises(InputError, match="mass_kg"):
        segment_parameters(-3, 1.7)
    with pytest.raises(InputError, match="sex"):
        segment_parameters(70, 1.7, "x")
    assert segment_parameters(70, 1.7, "F")["thigh_r"].mass_kg == pytest.approx(0.1478 * 70)


def test_rotation_keeps_principal_moments():
    seg = segment_parameters(**SUBJECT1)["foot_l"]
    c, s = np.cos(0.4), np.sin(0.4)
    R = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    rot = rotate_segment(seg, R)
    np.testing.assert_allclose(np.linalg.eigvalsh(rot.inertia_kgm2), np.sort(np.diag(seg.inertia_kgm2)))
    np.testing.assert_allclose(np.linalg.norm(rot.com_m), np.linalg.norm(seg.com_m))


def test_plug_in_gaits_legs_take_its_masses_coms_and_radii():
    """``legs="plug_in_gait"``: thigh, shank and foot by Plug-in Gait's table (mass % of body mass, CoM % of the
    length from the proximal end, one transverse radius of gyration, none about the long axis), computed here
    from the numbers themselves; pelvis and HAT stay de Leva's and the masses still sum to the body's."""
    segs = segment_parameters(**SUBJECT1, thigh_length_m=0.475, shank_length_m=0.43, legs="plug_in_gait")
    plain = segment_parameters(**SUBJECT1, thigh_length_m=0.475, shank_length_m=0.43)
    for key, length, mass_pct, com_pct, radius_pct in (("thigh_r", 0.475, 10.0, 43.3, 54.0),
                                                       ("shank_l", 0.43, 4.65, 43.3, 30.2)):
        seg, m = segs[key], mass_pct / 100 * 73.0
        assert seg.mass_kg == pytest.approx(m)
        np.testing.assert_allclose(seg.com_m, [0.0, 0.0, -com_pct / 100 * length])  # down from HJC / KJC
        np.testing.assert_allclose(np.diag(seg.inertia_kgm2), [m * (radius_pct / 100 * length) ** 2] * 2 + [0.0],
                                   atol=1e-15)
    assert segs["foot_r"].mass_kg == pytest.approx(0.0145 * 73.0)
    assert segs["pelvis"].mass_kg == plain["pelvis"].mass_kg
    assert sum(s.mass_kg for s in segs.values()) == pytest.approx(73.0, abs=1e-12)
    with pytest.raises(ValueError, match="legs"):
        segment_parameters(**SUBJECT1, legs="dempster")
