"""Plate contacts on every real trial with plates in ``../shared/data``: which foot stood on which plate.

The expected table is the survey of docs/plates_real.md, made without gaitcli: each file's heel and toe markers
(ezc3d, lab axes) against its plates' outlines and heights, in the frames where the plate's vertical force is above
20 N. No plate of these files is stood on by two feet at once, so no contact may be flagged; the first frame of
each contact is the survey's within 3 frames (the survey samples the force every 1/marker-rate, gaitcli
interpolates the raw force's crossing). Before the noise spikes were dropped, the stair trial's plate 1 opened
15 frames (125 ms) before the left foot's contact and its plate 2 spanned the whole trial.
"""

from __future__ import annotations

import shutil
import warnings

import pytest

from gaitcli.run.pipeline import load_recording
from gaitcli.run.trial import open_trial
from gaitcli.signal.stage import FilterConfig, filter_trial
from tests.conftest import REPO

pytestmark = pytest.mark.shared

#: the lab's heel and toe markers where no bundled preset names them
HELEN_HAYES = "mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_set: plug_in_gait\n"
BTS = "mass_kg: 70.0\nstature_m: 1.75\nsex: male\nmarker_map: {r heel: CAr, l heel: CAl, r met: MT2r, l met: MT2l}\n"
EXAMPLES = REPO / "docs" / "examples"

#: file → (subject.yaml text or example folder, {plate name: (foot, first loaded file frame)}), from the survey
SURVEY = {
    "c3d/walking2.c3d": ("walking2", {"plate1": ("r", 670), "plate2": ("l", 564)}),
    "c3d/walking5.c3d": ("walking2", {"plate1": ("l", 492), "plate2": ("r", 597)}),
    "c3d/Qualisys.c3d": ("qualisys", {"plate1": ("l", 720), "plate2": ("r", 813)}),
    "c3d/BTS.c3d": (BTS, {"plate1": ("l", 353), "plate4": ("r", 401), "plate5": ("l", 451)}),
    "emg/Gait.c3d": (HELEN_HAYES, {"plate1": ("l", 258), "plate2": ("r", 210)}),
    "pig/Movement_trial.c3d": (None, {"plate1": ("l", 925), "plate2": ("r", 859), "plate3": ("l", 800),
                                      "plate4": ("r", 737)}),
}


@pytest.mark.parametrize("name", list(SURVEY))
def test_each_real_plate_is_given_to_the_one_foot_that_stood_on_it(name, shared_c3d_dir, tmp_path):
    source = shared_c3d_dir.parent / name
    if not source.is_file():
        pytest.skip(f"../shared/data/{name} is not present")
    subject, expected = SURVEY[name]
    shutil.copy(source, tmp_path / "trial.c3d")  # a link out of the folder is refused
    if subject is None:  # the Vicon session: its .vsk describes the subject
        shutil.copy(source.parent / "Test.vsk", tmp_path / "Test.vsk")
    elif "\n" in subject:
        (tmp_path / "subject.yaml").write_text(subject)
    else:
        (tmp_path / "subject.yaml").write_text((EXAMPLES / subject / "subject.yaml").read_text())
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        recording = load_recording(open_trial(tmp_path))
        result = filter_trial(recording, FilterConfig(events="detect"))
    first = recording.markers.first_frame
    found = {c.plate_name: (c.side, c.first_frame + first) for c in result.contacts}
    assert {p: side for p, (side, _) in found.items()} == {p: side for p, (side, _) in expected.items()}
    for plate, (_, frame) in expected.items():
        assert abs(found[plate][1] - frame) <= 3, plate
    assert not [c for c in result.contacts if c.flag]
    assert not [w for w in said if "both feet" in str(w.message) or "not assigned" in str(w.message)]
