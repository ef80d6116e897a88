"""The recorded synthetic trial and its options (``gaitcli.synth.recording``)."""

from __future__ import annotations

import pytest

from gaitcli.errors import InputError
from gaitcli.synth import simulate_trial


def test_period_outside_walking_range_is_an_input_error():
    with pytest.raises(InputError, match="period"):
        simulate_trial(period_s=0.2, strides=1)


def test_three_plates_measure_three_consecutive_stances_each_wholly():
    """``plates=3``: the middle stances left, right, left, each under its own plate; each plate's force (no plate
    noise) is the true load of its foot over that stance, at the marker frames, and nothing else."""
    import numpy as np

    trial = simulate_trial(seed=2, strides=3, plates=3, plate_noise_N=0.0)
    assert trial.plate_feet == ["l", "r", "l"] and len(trial.plates) == 3
    step = int(trial.plates[0].rate_hz / trial.markers.rate_hz)
    on_plate = {}
    for _, frame, side, kind, on in trial.events:
        if on:
            on_plate.setdefault(side, []).append((kind, frame))
    assert [k for k, _ in on_plate["l"]] == ["heel_strike", "toe_off", "heel_strike", "toe_off"]
    for plate, side in zip(trial.plates, trial.plate_feet):
        force = plate.force_N[::step][:trial.markers.n_frames, 2]
        loaded = force > 0
        np.testing.assert_allclose(force[loaded], trial.feet[side]["force_N"][loaded, 2], rtol=1e-12)
        assert loaded.sum() > 40  # a whole stance, > 0.4 s at 100 Hz
    with pytest.raises(InputError, match="plates"):
        simulate_trial(plates=4)
    with pytest.raises(InputError, match="plates"):
        simulate_trial(plates=3, shared_plate=True)


def test_a_120_hz_trial_is_the_100_hz_walk_on_a_finer_grid():
    """``marker_rate_hz=120``: markers at 120 Hz, plates at 1200 Hz (ten samples a frame), the designed cycle on
    the 1200-Hz grid. Both trials start 0.275 s into the cycle (a quarter of the 1.1 s period), so every 0.05 s
    their frames coincide (100-Hz frame 5m, 120-Hz frame 6m): there the coordinates, the noise-free markers, the
    plates' vertical force and the true joint moments are the 100-Hz walk's, as far as the two grids differ
    (measured: the pelvis 1.6 mm further after two cycles, the stride the grid gives; angles 4e-4 rad; 0.8 N;
    0.4 N·m), and the events lie within one 1000-Hz sample of each other, each at the 120-Hz frame of its own
    time."""
    import numpy as np

    exact = dict(seed=0, strides=1, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0)
    slow, fast = simulate_trial(**exact), simulate_trial(marker_rate_hz=120.0, **exact)
    assert fast.markers.rate_hz == 120.0 and fast.static.rate_hz == 120.0
    assert all(p.rate_hz == 1200.0 for p in fast.plates)
    assert fast.plates[0].force_N.shape[0] == 10 * fast.markers.n_frames
    assert fast.markers.n_frames == pytest.approx(1.2 * slow.markers.n_frames, abs=2)
    common = min(slow.markers.n_frames // 5, fast.markers.n_frames // 6)
    a, b = np.arange(common) * 5, np.arange(common) * 6
    np.testing.assert_allclose(fast.q[b, :3], slow.q[a, :3], atol=2e-3)
    np.testing.assert_allclose(fast.q[b, 3:], slow.q[a, 3:], atol=1e-3)
    np.testing.assert_allclose(fast.markers.positions_m[b], slow.markers.positions_m[a], atol=2e-3)
    np.testing.assert_allclose(fast.plates[0].force_N[b * 10, 2], slow.plates[0].force_N[a * 10, 2], atol=1.5)
    np.testing.assert_allclose(fast.joint_moments_Nm[b], slow.joint_moments_Nm[a], atol=0.8)
    assert [(s, k, on) for _, _, s, k, on in fast.events] == [(s, k, on) for _, _, s, k, on in slow.events]
    for (t_fast, frame, *_), (t_slow, *_) in zip(fast.events, slow.events):
        assert abs(t_fast - t_slow) <= 1e-3 and frame == round(t_fast * 120.0)


def test_medial_markers_ride_thigh_and_shank_where_the_calibration_puts_the_centres():
    """``medial_markers=True`` (Plug-in Gait): RKNM/LKNM and RMED/LMED in walk and static. Noise-free, the knee
    centre is KNE's and KNM's midpoint and the de Leva ankle centre (knee centre + 1.0145 × (mid-malleoli − knee
    centre)) is the true ankle centre, in every frame; the marker sets other than Plug-in Gait refuse them, and a
    marker rate outside 50–500 Hz is refused."""
    import numpy as np

    from gaitcli.kinematics.joint_centres import ankle_joint_centre

    trial = simulate_trial(seed=0, strides=1, noise_mm=0.0, artefact_mm=0.0, marker_set="plug_in_gait",
                           medial_markers=True)
    centres = trial.joint_centres_m()
    for s, lab in (("r", "R"), ("l", "L")):
        knee = (trial.markers.get(f"{lab}KNE") + trial.markers.get(f"{lab}KNM")) / 2
        np.testing.assert_allclose(knee, centres[f"KJC{s}"], atol=1e-9)
        ankle = ankle_joint_centre(trial.markers.get(f"{lab}ANK"), trial.markers.get(f"{lab}MED"), knee)
        np.testing.assert_allclose(ankle, centres[f"AJC{s}"], atol=1e-9)
        assert f"{lab}KNM" in trial.static.labels and f"{lab}MED" in trial.static.labels
    with pytest.raises(InputError, match="medial_markers"):
        simulate_trial(medial_markers=True)
    with pytest.raises(InputError, match="marker_rate_hz"):
        simulate_trial(marker_rate_hz=20.0)
