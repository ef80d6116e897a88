"""Reference gait for Jdev (gaitcli/predict/reference.py): statistics with known answers, the left leg moved to
the right-heel-strike cycle, the SD floor, stride normalisation, and the CSV round trip with its errors."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.io.outputs import write_table
from gaitcli.predict.reference import VARIABLES, build_reference, jdev_sd, leg_cycles, read_reference
from gaitcli.signal.bands import SD_FLOOR
from gaitcli.signal.cycles import CYCLE_PCT


def strides(level: float, count: int = 2, spread: float = 10.0) -> list[np.ndarray]:
    """``count`` (101, 5) strides: variable k is level + k + spread·(i − mean i) + the cycle % / 10."""
    out = []
    for i in range(count):
        cycle = np.column_stack([level + k + spread * (i - (count - 1) / 2) + CYCLE_PCT / 10 for k in range(5)])
        out.append(cycle)
    return out


def test_mean_sd_and_the_floor_by_hand():
    ref = build_reference(strides(0.0), strides(100.0), left_offset_pct=0.0)
    hip_r, grf_z_r, hip_l = "hip_r_flexion_deg", "grf_z_r_N_per_kg", "hip_l_flexion_deg"
    np.testing.assert_allclose(ref.mean[hip_r], CYCLE_PCT / 10)  # the two strides' mean
    np.testing.assert_allclose(ref.sd[hip_r], 10 / np.sqrt(2))  # ±5 about the mean, ddof 1: 7.07
    np.testing.assert_allclose(ref.mean[grf_z_r], 4 + CYCLE_PCT / 10)
    # the left leg is moved as a periodic curve: its 100 % is its 0 % (this ramp is not periodic)
    np.testing.assert_allclose(ref.mean[hip_l][:100], 100 + CYCLE_PCT[:100] / 10)
    one = build_reference(strides(0.0, count=1), strides(0.0, count=1), left_offset_pct=0.0)
    np.testing.assert_allclose(one.sd[hip_r], 0.0)  # one stride: SD 0, as measured
    floored = build_reference(strides(0.0, count=1), strides(0.0, count=1), left_offset_pct=0.0, sd_floor=True)
    np.testing.assert_allclose(floored.sd[hip_r], SD_FLOOR["_deg"])  # raised to the floor
    np.testing.assert_allclose(floored.sd[grf_z_r], SD_FLOOR["_N_per_kg"])
    # Jdev divides by the floored SDs whatever the reference holds
    np.testing.assert_array_equal(jdev_sd(one.arrays(VARIABLES)[1]), floored.arrays(VARIABLES)[1])
    np.testing.assert_array_equal(jdev_sd(ref.arrays(VARIABLES)[1]), np.maximum(ref.arrays(VARIABLES)[1],
                                                                                 floored.arrays(VARIABLES)[1]))
    assert list(ref.strides.values()) == [2] * 10


def test_the_left_leg_moves_to_the_right_heel_strike_cycle():
    # a left curve over its own cycle, seen from a right-heel-strike cycle in which the left strikes at 50 %
    left = [np.column_stack([np.sin(2 * np.pi * CYCLE_PCT / 100) for _ in range(5)])]
    ref = build_reference(strides(0.0, count=1), left, left_offset_pct=50.0)
    hip_l = "hip_l_flexion_deg"
    np.testing.assert_allclose(ref.mean[hip_l], np.sin(2 * np.pi * (CYCLE_PCT - 50) / 100), atol=1e-12)


def test_a_variable_no_stride_gives_is_an_error():
    right = strides(0.0, count=1)
    right[0][:, 3:] = np.nan  # no stride with the right foot's load known
    with pytest.raises(InputError, match="no stride gives grf_x_r_N_per_kg, grf_z_r_N_per_kg"):
        build_reference(right, strides(0.0, count=1))


def test_strides_are_normalised_and_unknown_loads_left_out():
    t = np.arange(0, 3.0, 0.01)
    values = np.column_stack([t, 2 * t, 3 * t, 4 * t, 5 * t])
    known = np.ones(t.size, bool)
    known[(t > 1.6) & (t < 1.7)] = False  # the second stride's load was not measured for a moment
    cycles = leg_cycles(t, values, known, [(0.2, 1.2), (1.2, 2.4)])
    np.testing.assert_allclose(cycles[0][:, 0], 0.2 + CYCLE_PCT / 100, atol=1e-12)  # linear: interpolation exact
    assert np.isfinite(cycles[0]).all()
    assert np.isfinite(cycles[1][:, :3]).all() and np.isnan(cycles[1][:, 3:]).all()


def test_csv_round_trip_and_errors(tmp_path):
    ref = build_reference(strides(0.0), strides(50.0))
    path = tmp_path / "ref.csv"
    write_table(path, ref.columns(), float_format="%.10g")
    back = read_reference(path)
    np.testing.assert_allclose(back.arrays()[0], ref.arrays()[0], rtol=1e-9)
    np.testing.assert_allclose(back.arrays()[1], ref.arrays()[1], rtol=1e-9)
    columns = ref.columns()
    del columns["knee_l_flexion_deg_sd"]
    write_table(tmp_path / "short.csv", columns)
    with pytest.raises(InputError, match=r"short.csv: knee_l_flexion_deg_sd: missing column"):
        read_reference(tmp_path / "short.csv")
    columns = ref.columns()
    columns["grf_z_l_N_per_kg_sd"] = -np.ones(101)
    write_table(tmp_path / "negative.csv", columns)
    with pytest.raises(InputError, match="grf_z_l_N_per_kg_sd: expected means and standard deviations ≥ 0"):
        read_reference(tmp_path / "negative.csv")
    with pytest.raises(InputError, match="reference file not found"):
        read_reference(tmp_path / "none.csv")


def test_the_reference_between_its_samples_passes_through_them_with_a_continuous_slope():
    # Jdev (5.28) must be smooth in the phase durations: the curves interpolate the 1 % samples and their slope
    # does not jump there (a linear interpolant's jumps by the samples' second difference), across 0/100 % too
    import casadi as ca

    from gaitcli.predict.reference import reference_curves
    from gaitcli.resources import bundled_reference

    reference = read_reference(bundled_reference())
    mean_at, sd_at = reference_curves(reference)
    mean, sd = reference.arrays(VARIABLES)
    np.testing.assert_allclose(np.array(mean_at(CYCLE_PCT[None, :])).T, mean, atol=1e-10)
    np.testing.assert_allclose(np.array(sd_at(CYCLE_PCT[None, :])).T, jdev_sd(sd), atol=1e-10)
    pct = ca.MX.sym("pct")
    slope = ca.Function("slope", [pct], [ca.jacobian(mean_at(pct), pct)])
    for sample in (0.0, 37.0, 63.0, 100.0):
        below, above = np.array(slope(sample - 1e-7)), np.array(slope(sample + 1e-7))
        assert np.max(np.abs(below - above)) < 1e-4 * max(1.0, np.max(np.abs(below)))
    assert np.abs(np.diff(mean[36:39], 2, axis=0)).max() > 1e-2  # where a linear interpolant's slope would jump
