"""One noise-free synthetic walk of the sample subject and its ground reactions, shared by the synth tests."""

from __future__ import annotations

import pytest

from gaitcli.synth import ground_reactions, simulate_trial


@pytest.fixture(scope="module")
def walk():
    trial = simulate_trial(condition="normal", seed=0, noise_mm=0.0, artefact_mm=0.0, plate_noise_N=0.0,
                           strides=1, mass_kg=55.0, stature_m=1.65, period_s=1.40)
    design, params = trial.design, trial.calibration.body
    qd, qdd, feet, clip = ground_reactions(design, params)
    return design, params, qd, qdd, feet, clip
