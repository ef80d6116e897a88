"""Synthetic trial folders with known truth (``gait synth``).

A periodic walking motion of the 27-DoF model (:mod:`~gaitcli.synth.gait`);
ground reactions exactly consistent with it, split between the feet
(:mod:`~gaitcli.synth.ground`); the markers and force plates that record it
(:mod:`~gaitcli.synth.recording`); and the trial folder written from them
(:mod:`~gaitcli.synth.folder`).
"""

from gaitcli.synth.folder import subject_yaml, write_trial
from gaitcli.synth.gait import (
                                ANALOG_RATE_HZ,
                                CONDITIONS,
                                Condition,
                                GaitDesign,
                                Geometry,
                                balanced_gait,
                                design_gait,
                                leg_angles,
)
from gaitcli.synth.ground import ground_reactions, split_between_feet, whole_body_cop
from gaitcli.synth.recording import MARKER_BODY, MARKER_RATE_HZ, SyntheticTrial, simulate_trial

__all__ = ["ANALOG_RATE_HZ", "CONDITIONS", "Condition", "GaitDesign", "Geometry", "MARKER_BODY",
           "MARKER_RATE_HZ", "SyntheticTrial", "balanced_gait", "design_gait", "ground_reactions", "leg_angles",
           "simulate_trial", "split_between_feet", "subject_yaml", "whole_body_cop", "write_trial"]
