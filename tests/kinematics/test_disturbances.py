"""Disturbances (Tables A.2–A.3): adding a mass to a segment (parallel-axis theorem) and the presets."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.kinematics.anthropometry import segment_parameters
from gaitcli.kinematics.disturbances import (
    DISTURBANCE_TABLE,
    WEIGHT_BAND_ABOVE_ANKLE_M,
    Disturbance,
    add_disturbance,
    apply_disturbances,
    combine,
    preset_disturbances,
)
from gaitcli.kinematics.model import BODIES

SUBJECT1 = dict(mass_kg=73.0, stature_m=1.792)  # Tables A.4-A.5


def test_parallel_axis_combination_by_hand():
    seg = segment_parameters(**SUBJECT1)["shank_r"]
    base = type(seg)(2.0, np.zeros(3), np.diag([1.0, 2.0, 3.0]), 0.4, np.array([0, 0, -1.0]), "KJC")
    out = combine(base, 1.0, [0.1, 0.1, 0.1], [0.3, 0.3, 0.0])
    # CoM moves by m2 o / (m1 + m2) = (0.1, 0.1, 0); by hand about the new CoM:
    # Ixx = 1 + 2*0.1^2 + 0.1 + 1*0.2^2 = 1.16, Iyy = 2.16, Izz = 3 + 2*0.02 + 0.1 + 1*0.08 = 3.22,
    # Ixy = -(2*0.1*0.1 + 1*0.2*0.2) = -0.06
    expected = np.array([[1.16, -0.06, 0.0], [-0.06, 2.16, 0.0], [0.0, 0.0, 3.22]])
    np.testing.assert_allclose(out.com_m, [0.1, 0.1, 0.0], atol=1e-15)
    np.testing.assert_allclose(out.inertia_kgm2, expected, atol=1e-14)
    assert out.mass_kg == 3.0


def test_combination_matches_a_point_cloud():
    rng = np.random.default_rng(3)
    clouds = [rng.normal(size=(50, 3)) * [0.05, 0.05, 0.2], rng.normal(size=(40, 3)) * 0.03 + [0.02, 0.01, -0.15]]
    weights = [np.full(50, 0.06), np.full(40, 0.04)]

    def body(points, w):
        c = w @ points / w.sum()
        r = points - c
        inertia = np.einsum("k,kij->ij", w, np.einsum("ki,ki->k", r, r)[:, None, None] * np.eye(3)
                            - np.einsum("ki,kj->kij", r, r))
        return w.sum(), c, inertia

    m1, c1, i1 = body(clouds[0], weights[0])
    m2, c2, i2 = body(clouds[1], weights[1])
    mt, ct, it = body(np.vstack(clouds), np.concatenate(weights))
    seg = type(segment_parameters(**SUBJECT1)["pelvis"])(m1, c1, i1, 0.4, np.array([0, 0, 1.0]), "X")
    out = combine(seg, m2, i2, c2 - c1)
    np.testing.assert_allclose(out.com_m, ct, atol=1e-14)
    np.testing.assert_allclose(out.inertia_kgm2, it, atol=1e-14)
    assert out.mass_kg == pytest.approx(mt)


@pytest.mark.parametrize("preset, changes", [
    ("ankle_weight", {"shank_r": 1.719}),
    ("weight_band", {"shank_r": 1.719}),
    ("ski_boot", {"foot_r": 2.431}),
    ("ankle_fixed", {"foot_r": 0.999, "foot_l": 0.497}),
    ("fixation_shoe", {"foot_r": 0.999, "foot_l": 0.497}),
    ("shoes_subject1", {"foot_r": 0.319, "foot_l": 0.319}),
    ("knee_orthosis", {"thigh_r": 0.462, "shank_r": 0.462}),
    ("normal", {}),
])
def test_presets_add_exactly_the_table_masses(preset, changes):
    segs = segment_parameters(**SUBJECT1)
    out = apply_disturbances(segs, preset_disturbances(preset, segs))
    for b in BODIES:
        assert out[b].mass_kg - segs[b].mass_kg == pytest.approx(changes.get(b, 0.0), abs=1e-12)


def test_left_side_presets_mirror():
    segs = segment_parameters(**SUBJECT1)
    out = apply_disturbances(segs, preset_disturbances("ankle_weight", segs, side="l"))
    assert out["shank_l"].mass_kg - segs["shank_l"].mass_kg == pytest.approx(1.719)
    assert out["shank_r"].mass_kg == segs["shank_r"].mass_kg


def test_weight_band_sits_above_the_ankle():
    segs = segment_parameters(**SUBJECT1, shank_length_m=0.43)
    (band,) = preset_disturbances("ankle_weight", segs)
    position = segs["shank_r"].com_m + band.com_offset_m  # relative to the knee, along -z
    np.testing.assert_allclose(position, [0.0, 0.0, -(0.43 - WEIGHT_BAND_ABOVE_ANKLE_M)], atol=1e-15)
    np.testing.assert_allclose(band.inertia_kgm2, np.diag(DISTURBANCE_TABLE["weight_band"][1]))


def test_knee_orthosis_halves_recombine_to_the_table():
    segs = segment_parameters(**SUBJECT1, thigh_length_m=0.45, shank_length_m=0.43)
    halves = preset_disturbances("knee_orthosis", segs)
    # both halves relative to the knee joint centre (straight leg, segment axes = global)
    at_knee = [segs["thigh_r"].com_m + halves[0].com_offset_m - segs["thigh_r"].axis * 0.45,
               segs["shank_r"].com_m + halves[1].com_offset_m]
    whole = type(segs["pelvis"])(halves[0].mass_kg, at_knee[0], halves[0].inertia_kgm2, 0.0, np.zeros(3), "KJC")
    whole = combine(whole, halves[1].mass_kg, halves[1].inertia_kgm2, at_knee[1] - at_knee[0])
    m, diag = DISTURBANCE_TABLE["knee_orthosis"]
    assert whole.mass_kg == pytest.approx(m)
    np.testing.assert_allclose(whole.com_m, 0.0, atol=1e-15)
    np.testing.assert_allclose(whole.inertia_kgm2, np.diag(diag), atol=1e-15)
    assert np.all(np.diag(halves[0].inertia_kgm2) > 0)


def test_disturbance_errors():
    segs = segment_parameters(**SUBJECT1)
    with pytest.raises(InputError, match="segment"):
        add_disturbance(segs, "arm_r", 1.0, [0, 0, 0])
    with pytest.raises(InputError, match=r"disturbance: got .jetpack. \(expected one of normal, ankle_weight"):
        preset_disturbances("jetpack", segs)
    with pytest.raises(InputError, match="inertia"):
        apply_disturbances(segs, [Disturbance("foot_r", 1.0, np.ones(4))])
