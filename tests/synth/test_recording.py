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
