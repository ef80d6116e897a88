"""Which channel records which muscle (gaitcli/emg/channels.py): labels as labs write them, a lab's own
map, and the errors that name what is wrong."""

from __future__ import annotations

import pytest

from gaitcli.emg.channels import channel_map, muscle_of
from gaitcli.errors import InputError

#: the two real trials' EMG labels (../shared/data: c3d/BTS.c3d, emg/Gait.c3d) and what they record
BTS = {"Left Rectus femoris": "rectus_femoris_l", "Right Rectus femoris": "rectus_femoris_r",
       "Left Semimembranosus": "hamstrings_l", "Right Semimembranosus": "hamstrings_r",
       "Left Tibialis anterior": "tibialis_anterior_l", "Right Tibialis anterior": "tibialis_anterior_r",
       "Left Gastrocnemius medialis": "gastrocnemius_l", "Right Gastrocnemius medialis": "gastrocnemius_r"}
GAIT = {f"{side.upper()}{word}": f"{muscle}_{side}" for side in ("l", "r") for word, muscle in (
    ("REC", "rectus_femoris"), ("VAS", "vasti"), ("GRF", "glutei"), ("ISC", "hamstrings"), ("BIC", "biceps_femoris"),
    ("TIB", "tibialis_anterior"), ("SOL", "soleus"), ("JUM", "gastrocnemius"))}


@pytest.mark.parametrize("label, muscle", [
    ("RTIBA", "tibialis_anterior_r"), ("R TA", "tibialis_anterior_r"), ("Voltage.RGAS", "gastrocnemius_r"),
    ("TA R", "tibialis_anterior_r"), ("L_Soleus", "soleus_l"), ("EMG1 R TA", "tibialis_anterior_r"),
    ("Sensor 4. R-VL", "vasti_r"), ("LRF", "rectus_femoris_l"), ("Fx1", None), ("Mz3", None), ("RF", None),
    ("R", None), ("EMG 2", None)])
def test_preset_labels(label, muscle):
    assert muscle_of(label) == muscle


def test_the_real_trials_labels_name_their_muscles():
    assert channel_map(list(BTS) + ["Fz1"]) == BTS
    assert channel_map(list(GAIT)) == GAIT


def test_a_labs_map_is_taken_as_given_and_names_what_it_misses():
    labels = ["EMG1", "EMG2", "EMG3"]
    assert channel_map(labels, {"EMG1": "tibialis_anterior_r", "EMG3": "Soleus_L"}) == {
        "EMG1": "tibialis_anterior_r", "EMG3": "soleus_l"}
    with pytest.raises(InputError, match="channels EMG4, EMG5 are not in the trial") as err:
        channel_map(labels, {"EMG4": "soleus_r", "EMG1": "vasti_r", "EMG5": "vasti_l"}, source="trial.c3d")
    assert err.value.field == "emg"
    with pytest.raises(InputError, match="expected a muscle and its side") as err:
        channel_map(labels, {"EMG1": "tibialis_anterior"})
    assert err.value.field == "emg.EMG1"


def test_two_channels_of_one_muscle_are_refused():
    with pytest.raises(InputError, match="RTIBA and R TA both record tibialis_anterior_r"):
        channel_map(["RTIBA", "R TA"])


def test_the_model_muscles_are_the_muscle_models():
    # emg/ may not import muscles/ (docs/architecture.md): the names are written twice, kept equal here
    from gaitcli.emg.channels import MODEL_MUSCLES
    from gaitcli.muscles.parameters import MUSCLE_NAMES

    assert MODEL_MUSCLES == MUSCLE_NAMES
