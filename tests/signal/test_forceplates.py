"""Plate loads: COP and free moment from a known wrench, masking, resampling, per-foot sums."""

from __future__ import annotations

import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate
from gaitcli.errors import InputError
from gaitcli.signal import forceplates
from gaitcli.signal.butterworth import lowpass
from gaitcli.signal.events import detect_events
from gaitcli.signal.forceplates import (
    PlateLoad,
    centre_of_pressure,
    combine_loads,
    plate_load,
    resample_to_frames,
    resting_offsets,
)

ANALOG_HZ = 1000.0
MARKER_HZ = 100.0
CENTRE = np.array([1.0, 0.3, 0.0])
CORNERS = CENTRE + np.array([[0.3, 0.2, 0], [-0.3, 0.2, 0], [-0.3, -0.2, 0], [0.3, -0.2, 0]])


def _stance(t, t0=0.5, duration=0.6):
    """Half-sine load envelope, 0 outside [t0, t0 + duration]."""
    s = (t - t0) / duration
    return np.where((s > 0) & (s < 1), np.sin(np.pi * np.clip(s, 0, 1)), 0.0)


def _plate_from(cop_xy, force, free, *, noise_N=0.0, seed=0):
    """A plate whose wrench about its surface centre is ``force`` at ``cop_xy`` plus ``free`` about z."""
    r = np.zeros_like(force)
    r[:, :2] = np.asarray(cop_xy) - CENTRE[:2]
    moment = np.cross(r, force)
    moment[:, 2] += free
    rng = np.random.default_rng(seed)
    force = force + rng.normal(0, noise_N, force.shape)
    moment = moment + rng.normal(0, noise_N / 5, moment.shape)
    return ForcePlate("FP1", force, moment, CENTRE, CORNERS, ANALOG_HZ)


def _filtered_on_plate(plate, threshold_N, cutoff_hz=6.0):
    """The plate's wrench (force, moment) zeroed where its raw vertical force is at most ``threshold_N``, then
    filtered and taken at the marker frames: what ``plate_load`` is defined to give where loaded."""
    wrench = np.concatenate([plate.force_N, plate.moment_Nm], 1)
    wrench = np.where(plate.force_N[:, 2:3] > threshold_N, wrench, 0.0)
    filtered = lowpass(wrench, rate_hz=ANALOG_HZ, cutoff_hz=cutoff_hz)[::10]
    return filtered[:, :3], filtered[:, 3:]


def _known_wrench(n_s=1.6):
    t = np.arange(int(n_s * ANALOG_HZ)) / ANALOG_HZ
    env = _stance(t)
    force = np.stack([-120 * np.sin(2 * np.pi * (t - 0.5) / 0.6) * env, 35 * env, 750 * env], axis=1)
    free = 6.0 * env * np.cos(np.pi * (t - 0.5) / 0.6)
    return t, force, free


def test_known_cop_and_free_moment():
    t, force, free = _known_wrench()
    cop_xy = CENTRE[:2] + np.array([0.12, -0.05])
    load = plate_load(_plate_from(np.broadcast_to(cop_xy, (len(t), 2)), force, free),
                      cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ)
    assert load.rate_hz == MARKER_HZ and load.n_frames == 160
    on = load.loaded
    assert on.sum() > 50
    cop_error_m = np.linalg.norm(load.cop_m[on, :2] - cop_xy, axis=1)
    assert cop_error_m.max() < 1e-3
    assert np.all(load.cop_m[on, 2] == 0.0)
    # the filter is linear and r is constant, so T_z is the filtered (on-plate) free moment to round-off
    on_plate = force[:, 2] > 20.0
    free_f = lowpass(np.where(on_plate, free, 0.0), rate_hz=ANALOG_HZ, cutoff_hz=6.0)[::10]
    np.testing.assert_allclose(load.free_moment_Nm[on], free_f[on], atol=1e-9)
    force_f = lowpass(np.where(on_plate[:, None], force, 0.0), rate_hz=ANALOG_HZ, cutoff_hz=6.0)[::10]
    np.testing.assert_allclose(load.force_N[on], force_f[on], atol=1e-9)


def test_sliding_cop_path_and_noise():
    """COP sliding 0.2 m heel to toe with lateral drift, 2 N noise.

    The COP comes from filtered moments and forces, and the filter acts on the
    product r(t) x F(t) rather than on F alone, so the COP of the filtered load is
    not exactly the true COP where the load changes fast. Measured without noise:
    2.5 mm at 10 % of peak F_z (the loading edge), 1.0 mm above 30 %; the noise adds
    under 1 mm.
    """
    t, force, free = _known_wrench()
    s = np.clip((t - 0.5) / 0.6, 0, 1)
    cop_xy = np.stack([CENTRE[0] - 0.1 + 0.2 * s, CENTRE[1] + 0.02 * np.sin(np.pi * s)], axis=1)
    load = plate_load(_plate_from(cop_xy, force, free, noise_N=2.0, seed=3), cutoff_hz=6.0, threshold_N=20.0,
                      rate_hz=MARKER_HZ)
    fz = force[::10, 2]
    assert np.all(load.loaded[fz > 75.0])
    cop_error_m = np.linalg.norm(load.cop_m[:, :2] - cop_xy[::10], axis=1)
    assert cop_error_m[fz > 75.0].max() < 4e-3
    assert cop_error_m[fz > 225.0].max() < 2e-3
    assert np.abs(load.free_moment_Nm[fz > 75.0] - free[::10][fz > 75.0]).max() < 0.2


def test_threshold_masking():
    t, force, free = _known_wrench()
    plate = _plate_from(np.broadcast_to(CENTRE[:2], (len(t), 2)), force, free, noise_N=3.0, seed=4)
    load = plate_load(plate, cutoff_hz=6.0, threshold_N=50.0, rate_hz=MARKER_HZ)
    force_f, _ = _filtered_on_plate(plate, 50.0)
    # loaded: the one run of positive filtered load around the contact (the filter's ringing lobes beside it
    # are not), which begins before and ends after the raw force crosses the threshold
    starts, stops = np.flatnonzero(np.diff(np.r_[0, load.loaded.astype(int), 0]) == 1), \
        np.flatnonzero(np.diff(np.r_[0, load.loaded.astype(int), 0]) == -1)
    assert starts.size == 1
    raw_on = np.flatnonzero(plate.force_N[::10, 2] > 50.0)
    assert starts[0] < raw_on[0] and stops[0] > raw_on[-1] + 1
    assert np.all(force_f[load.loaded, 2] > 0.05)
    np.testing.assert_allclose(load.force_N[load.loaded], force_f[load.loaded], atol=1e-9)
    # the load runs down to 0 at the edges: the step there is one frame's change of the filtered load through
    # 0 (9.5 N measured), not the threshold (50 N)
    edges = [starts[0], stops[0] - 1]
    assert np.abs(load.force_N[edges, 2]).max() < 0.25 * 50.0
    off = ~load.loaded
    assert off.sum() > 50
    assert np.all(load.force_N[off] == 0.0)
    assert np.isnan(load.cop_m[off]).all() and np.isnan(load.free_moment_Nm[off]).all()
    assert np.isfinite(load.cop_m[~off]).all() and np.isfinite(load.free_moment_Nm[~off]).all()
    assert load.threshold_N == 50.0
    np.testing.assert_array_equal(load.raw_vertical_force_N, plate.force_N[:, 2])
    assert load.raw_rate_hz == ANALOG_HZ
    np.testing.assert_array_equal(load.corners_m, CORNERS)


def test_native_rate_and_resampling():
    t, force, free = _known_wrench()
    plate = _plate_from(np.broadcast_to(CENTRE[:2], (len(t), 2)), force, free)
    native = plate_load(plate, cutoff_hz=6.0, threshold_N=20.0)
    assert native.rate_hz == ANALOG_HZ and native.n_frames == len(t)
    framed = plate_load(plate, cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ)
    np.testing.assert_array_equal(framed.force_N, native.force_N[::10])  # first sample of each frame
    x = np.arange(23.0)
    np.testing.assert_array_equal(resample_to_frames(x, source_rate_hz=1000.0, rate_hz=100.0), [0.0, 10.0, 20.0])
    # a non-integer ratio: linear interpolation at the frame times
    y = resample_to_frames(np.stack([x, 2 * x], 1), source_rate_hz=250.0, rate_hz=60.0)
    np.testing.assert_allclose(y[:, 0], np.arange(y.shape[0]) * 250.0 / 60.0)
    np.testing.assert_allclose(y[:, 1], 2 * y[:, 0])


def test_frame_means_average_the_samples_centred_on_each_frame():
    """Nexus's per-frame load: frame k is the mean of the r = analog/marker-rate samples from k·r − r//2 (fewer at
    the ends); a NaN sample makes only its own frame unknown."""
    t, force, free = _known_wrench()
    plate = _plate_from(np.broadcast_to(CENTRE[:2], (len(t), 2)), force, free)
    unfiltered = plate_load(plate, cutoff_hz=0.0, threshold_N=20.0, rate_hz=MARKER_HZ, frame_means=True)
    fz = np.asarray(force)[:, 2]
    for k in (40, 55, 70):  # loaded frames: the mean of samples 10k−5 … 10k+4
        assert unfiltered.force_N[k, 2] == pytest.approx(fz[10 * k - 5:10 * k + 5].mean(), rel=1e-12)
    x = np.arange(40.0)
    np.testing.assert_allclose(forceplates._frame_means(x, source_rate_hz=900.0, rate_hz=100.0),
                               [2.0, 9.0, 18.0, 27.0, 35.5])  # 0…4, 5…13, 14…22, 23…31, 32…39
    x[12] = np.nan
    got = forceplates._frame_means(x, source_rate_hz=900.0, rate_hz=100.0)
    assert np.isnan(got[1]) and np.isfinite(np.delete(got, 1)).all()


def test_moment_about_origin_reproduces_the_plate_wrench():
    t, force, free = _known_wrench()
    s = np.clip((t - 0.5) / 0.6, 0, 1)
    cop_xy = np.stack([CENTRE[0] - 0.1 + 0.2 * s, CENTRE[1] + 0.01 * s], axis=1)
    plate = _plate_from(cop_xy, force, free)
    load = plate_load(plate, cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ)
    force_f, moment_f = _filtered_on_plate(plate, 20.0)
    expected = moment_f + np.cross(CENTRE, force_f)  # M_O = M_C + C x F
    on = load.loaded
    np.testing.assert_allclose(load.moment_about_origin_Nm()[on], expected[on], atol=1e-9)


def test_centre_of_pressure_formula():
    force = np.array([[10.0, -20.0, 500.0]])
    r = np.array([[0.05, -0.03, 0.0]])
    moment = np.cross(r, force) + np.array([[0, 0, 2.5]])
    cop, free = centre_of_pressure(force, moment, [1.0, 2.0, 0.01])
    np.testing.assert_allclose(cop, [[1.05, 1.97, 0.01]])
    np.testing.assert_allclose(free, [2.5])


def test_combined_plates_equal_single_plate_when_foot_on_both(walk_factory):
    """Heel on one plate, forefoot on the next: their sum equals one large plate under the whole foot."""
    straddle = walk_factory(plates=[("r", 1, -0.2, 0.3, 0.4), ("r", 1, 0.1, 0.3, 0.4)], noise_N=0.0, noise_Nm=0.0)
    single = walk_factory(plates=[("r", 1, 0.0, 0.6, 0.4)], noise_N=0.0, noise_Nm=0.0)
    assert straddle.plate_stances == [{("r", 1)}, {("r", 1)}]
    loads = [plate_load(p, cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ) for p in straddle.plates]
    reference = plate_load(single.plates[0], cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ)
    detection = detect_events(loads, straddle.feet, straddle.pelvis, MARKER_HZ, 20.0)
    assert [c.side for c in detection.contacts] == ["r", "r"]
    feet = combine_loads(loads, detection.owner)
    both = loads[0].loaded & loads[1].loaded
    assert both.sum() > 30
    # each plate's raw load is zeroed below the threshold before the filter, and a plate under part of the
    # foot crosses it at other times than the whole foot's: the filter spreads that difference, at most a
    # fraction of the threshold (measured 4.6 N, 1.0 mm, 0.022 N·m of 650 N)
    np.testing.assert_allclose(feet["r"].force_N[both], reference.force_N[both], atol=0.25 * 20.0)
    np.testing.assert_allclose(feet["r"].cop_m[both], reference.cop_m[both], atol=1.5e-3)
    np.testing.assert_allclose(feet["r"].free_moment_Nm[both], reference.free_moment_Nm[both], atol=0.05)
    # everywhere: the per-foot force is the sum of the owned plates' forces; the left foot got nothing
    np.testing.assert_allclose(feet["r"].force_N, loads[0].force_N + loads[1].force_N, atol=1e-12)
    assert not feet["l"].loaded.any() and np.all(feet["l"].force_N == 0)
    # and the per-foot COP follows the true COP of the foot: to the filter effect (< 1 mm) where both
    # plates are loaded; where one plate is just below the threshold its share is dropped, which can
    # move the COP by up to 20 N x 0.15 m / 650 N = 4.6 mm (3.1 mm measured)
    truth_cop = straddle.foot_cop_m["r"][::10]
    t_hs = straddle.heel_strikes["r"][1]
    on_plates = (straddle.time_s > t_hs) & (straddle.time_s < t_hs + straddle.stance_s)
    strong = on_plates & (straddle.foot_force_N["r"][::10, 2] > 70.0)
    assert np.all(feet["r"].loaded[strong])
    error_m = np.linalg.norm(feet["r"].cop_m[:, :2] - truth_cop[:, :2], axis=1)
    assert error_m[strong & both].max() < 1e-3
    assert error_m[strong].max() < 4.6e-3


def test_combine_two_feet_on_two_plates_in_double_support(walk_factory):
    walk = walk_factory(plates=[("r", 1, 0.0, 0.6, 0.4), ("l", 1, 0.0, 0.6, 0.4)])
    loads = [plate_load(p, cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ) for p in walk.plates]
    owner = np.where(np.stack([load.loaded for load in loads]), np.array([["r"], ["l"]]), "")
    feet = combine_loads(loads, owner)
    for side, load in zip("rl", loads):
        np.testing.assert_allclose(feet[side].force_N, load.force_N, atol=1e-12)
        np.testing.assert_array_equal(feet[side].loaded, load.loaded)
        np.testing.assert_allclose(feet[side].cop_m[load.loaded], load.cop_m[load.loaded], atol=1e-12)
        np.testing.assert_allclose(feet[side].free_moment_Nm[load.loaded], load.free_moment_Nm[load.loaded],
                                   atol=1e-9)
    assert (loads[0].loaded & loads[1].loaded).sum() > 5  # the double support was on the plates


def test_bad_inputs_are_input_errors():
    t, force, free = _known_wrench()
    plate = _plate_from(np.broadcast_to(CENTRE[:2], (len(t), 2)), force, free)
    with pytest.raises(InputError) as info:
        plate_load(plate, cutoff_hz=6.0, threshold_N=-1.0)
    assert info.value.field == "threshold_N"
    with pytest.raises(InputError) as info:
        plate_load(plate, cutoff_hz=6.0, threshold_N=20.0, rate_hz=10.0)
    assert info.value.field == "cutoff_hz"
    bad = ForcePlate("FP9", force[:, :2], plate.moment_Nm, CENTRE, CORNERS, ANALOG_HZ)
    with pytest.raises(InputError):
        plate_load(bad, cutoff_hz=6.0, threshold_N=20.0)
    load = plate_load(plate, cutoff_hz=6.0, threshold_N=20.0, rate_hz=MARKER_HZ)
    with pytest.raises(InputError) as info:
        combine_loads([load], np.full((2, load.n_frames), "r"))
    assert info.value.field == "owner"
    assert isinstance(load, PlateLoad)


def test_a_plate_reading_a_load_with_no_foot_near_is_an_offset_run():
    # 100 Hz: 20 N of offset in frames 0-49 (no foot near), a foot's 700 N in 50-89 (near), 20 N again in 90-94
    # (5 frames: shorter than 0.1 s) and 6 N (below the 10 N limit) in 95-99
    fz = np.r_[np.full(50, 20.0), np.full(40, 700.0), np.full(5, 20.0), np.full(5, 6.0)]
    quiet = np.r_[np.ones(50, bool), np.zeros(40, bool), np.ones(10, bool)]
    assert resting_offsets(fz, quiet=quiet, rate_hz=100.0, limit_N=10.0) == [(0, 49, 20.0, 20.0)]
    assert resting_offsets(-fz, quiet=quiet, rate_hz=100.0, limit_N=10.0) == [(0, 49, -20.0, -20.0)]
