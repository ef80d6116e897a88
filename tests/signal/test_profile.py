"""The Gait Profile Score (gaitcli/signal/profile.py) on curves with known differences from a band: constant
offsets give GVS = |offset| and GPS = the RMS of the offsets; the pelvis counts once overall; what the band
lacks is left out."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.signal.bands import Band
from gaitcli.signal.cycles import CYCLE_PCT
from gaitcli.signal.profile import GPS_VARIABLES, gait_profile, gait_variable_score

WAVE = 20 * np.sin(2 * np.pi * CYCLE_PCT / 100)


def band_of(variables) -> Band:
    return Band({v: WAVE + k for k, v in enumerate(variables)}, {v: np.full(101, 3.0) for v in variables})


def test_constant_offsets_give_their_size():
    variables = [v for _, v in GPS_VARIABLES]
    band = band_of(variables)
    offsets = {"r": dict(zip([c.format(s="r") for c, _ in GPS_VARIABLES], [1, 2, 3, 4, 5, 6, 7, 8, 9])),
               "l": dict(zip([c.format(s="l") for c, _ in GPS_VARIABLES], [-2, -2, -2, 0, 0, 0, 0, 0, 3]))}
    means = {side: {c.format(s=side): band.mean[v] + offsets[side][c.format(s=side)] for c, v in GPS_VARIABLES}
             for side in ("r", "l")}
    profile = gait_profile(means, band)
    assert profile.gvs[("r", "knee_r_flexion")] == pytest.approx(7.0)
    assert profile.gvs[("l", "pelvis_tilt")] == pytest.approx(2.0)
    assert profile.gps_side["r"] == pytest.approx(np.sqrt(np.mean(np.square(range(1, 10)))))
    assert profile.gps_side["l"] == pytest.approx(np.sqrt((3 * 4 + 9) / 9))
    # overall: the left pelvis (2, 2, 2), the right leg's six (4…9) and the left leg's six (0…0, 3)
    overall = [2, 2, 2, 4, 5, 6, 7, 8, 9, 0, 0, 0, 0, 0, 3]
    assert profile.gps == pytest.approx(np.sqrt(np.mean(np.square(overall))))
    assert profile.as_dict()["gvs_deg"]["left"]["foot_l_progression"] == pytest.approx(3.0)


def test_a_wave_of_known_rms_and_a_band_without_pelvis():
    legs = [v for c, v in GPS_VARIABLES if not c.startswith("pelvis")]
    band = band_of(legs)
    shift = 4 * np.cos(2 * np.pi * CYCLE_PCT / 100)  # RMS over the 101 points: 4·sqrt(mean(cos²))
    expected = 4 * np.sqrt(np.mean(np.cos(2 * np.pi * CYCLE_PCT / 100) ** 2))
    assert gait_variable_score(band.mean["knee_flexion_deg"] + shift, band.mean["knee_flexion_deg"]) == \
        pytest.approx(expected)
    means = {"r": {c.format(s="r"): (band.mean[v] + shift if v in band.mean else np.zeros(101))
                   for c, v in GPS_VARIABLES}}
    profile = gait_profile(means, band)
    assert len(profile.gvs) == 6 and profile.gps == pytest.approx(expected)  # the pelvis: not in the band
    with pytest.raises(ValueError):
        gait_profile({"r": {"knee_r_flexion": np.full(101, np.nan)}}, band)


def test_a_trial_far_slower_than_the_bands_walking_is_said():
    """Issue 52, item 6: the shared stair descent (0.49 m/s, stature 1.679 m) was plotted against the free-walking
    band unflagged. v̂ = v / √(g·L), L = 0.53 × stature: 0.49 / √(9.81 · 0.890) = 0.166, beyond 4 SD of the band's
    0.429 ± 0.026; the synthetic subject's 1.30 m/s at 1.78 m (v̂ 0.427) is within."""
    from gaitcli.signal.bands import speed_outside_band

    said = speed_outside_band(0.49, 0.530 * 1.679)
    assert said is not None and "0.49 m/s (0.17 in leg lengths" in said and "far below" in said
    assert speed_outside_band(1.30, 0.530 * 1.78) is None
    assert "far above" in speed_outside_band(2.4, 0.530 * 1.78)


def test_the_bands_speed_is_the_free_groups_in_the_shipped_table():
    """signal/ may not read predict/'s data: the band's speed is written down in bands.py; it must be the free
    group's of gaitcli/predict/data/schwartz2008_groups.csv (the workbook's)."""
    from gaitcli.predict.speed_reference import SpeedGroups
    from gaitcli.signal.bands import BAND_SPEED_DIMENSIONLESS

    groups = SpeedGroups.read()
    k = groups.names.index("free")
    assert BAND_SPEED_DIMENSIONLESS == pytest.approx((groups.mean["speed"][k], groups.sd["speed"][k]), abs=5e-4)
