"""The C3D EVENT group: read into :class:`Events` on the trial's time axis, and written back by the export.

The files are written with ezc3d's own ``add_event`` (minutes and seconds from the recording's frame 1, the
time base of Vicon Nexus and Qualisys): an event at file frame ``f`` is at ``(f - 1) / rate`` and, in a trial
whose first frame is ``F``, at ``(f - F) / rate`` on the trial's own axis, frame index ``f - F``.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import ezc3d
import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.errors import GaitWarning
from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d.events import gait_event
from gaitcli.io.c3d_write import add_points

RATE_HZ, FIRST, N = 100.0, 101, 40  # the trial holds file frames 101..140


def _file(path: Path, events=(), *, short=None) -> Path:
    """Four standing markers over frames FIRST..FIRST+N-1 (mm); ``events``: (file frame, label, context) added
    with ezc3d's add_event; ``short``: (file frame, label) as EVENT LABELS/TIMES without CONTEXTS."""
    labels = ["A", "B", "C", "D"]
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = np.array([RATE_HZ])
    c["parameters"]["POINT"]["LABELS"]["value"] = labels
    c["parameters"]["POINT"]["DESCRIPTIONS"]["value"] = [""] * 4
    c["parameters"]["POINT"]["UNITS"]["value"] = ["mm"]
    c["parameters"]["ANALOG"]["RATE"]["value"] = np.array([RATE_HZ])
    c["header"]["points"]["first_frame"] = FIRST - 1  # ezc3d counts from 0
    points = np.ones((4, 4, N))
    standing = np.array([[500.0, 500.0, 1700.0], [500.0, 420.0, 950.0], [500.0, 580.0, 950.0], [520.0, 450.0, 60.0]])
    points[:3] = standing.T[:, :, None] + np.arange(N) * np.array([20.0, 0.0, 0.0])[:, None, None]
    c["data"]["points"] = points
    c["data"]["meta_points"]["residuals"] = np.zeros((1, 4, N))
    c["data"]["meta_points"]["camera_masks"] = np.zeros((7, 4, N), dtype=bool)
    c["data"]["analogs"] = np.zeros((1, 0, N))
    for frame, label, context in events:
        c.add_event([0, (frame - 1) / RATE_HZ], context=context, label=label)
    if short:
        c.add_parameter("EVENT", "USED", len(short))
        c.add_parameter("EVENT", "LABELS", [label for _, label in short])
        c.add_parameter("EVENT", "TIMES", np.array([[0.0] * len(short), [(f - 1) / RATE_HZ for f, _ in short]]))
    c.write(str(path))
    return path


def _read(path):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", GaitWarning)
        rec = read_c3d(path, to_model_axes=False)
    return rec, [str(w.message) for w in caught if issubclass(w.category, GaitWarning)]


def test_vicon_events_are_read_on_the_trials_time_axis_and_the_rest_left_out(tmp_path):
    events = [(103, "Foot Strike", "Left"), (117, "Foot Off", "Right"), (140, "Foot Strike", "Right"),
              (101, "Foot Off", "Left"), (125, "Event", "General"), (130, "Foot Strike", "General"),
              (141, "Foot Off", "Left"), (90, "Foot Strike", "Right")]
    rec, said = _read(_file(tmp_path / "t.c3d", events))
    ev = rec.events
    assert ev.frame.tolist() == [0, 2, 16, 39]  # file frame − FIRST, sorted by time
    np.testing.assert_allclose(ev.time_s, [0.0, 0.02, 0.16, 0.39], atol=1e-9)
    assert ev.side.tolist() == ["l", "l", "r", "r"]
    assert ev.kind.tolist() == ["toe_off", "heel_strike", "toe_off", "heel_strike"]
    assert set(ev.source) == {"file"}
    assert any("2 gait event(s) outside the trial's 1.000–1.390 s dropped" in s for s in said), said
    assert any("1 foot event(s) without a Left/Right context" in s for s in said), said


def test_short_labels_without_contexts_carry_their_side(tmp_path):
    rec, said = _read(_file(tmp_path / "q.c3d", short=[(105, "LHS"), (110, "RTO"), (120, "RHS"), (125, "LTO")]))
    assert not [s for s in said if "EVENT" in s]
    assert [(f, s, k) for f, s, k in zip(rec.events.frame, rec.events.side, rec.events.kind)] == [
        (4, "l", "heel_strike"), (9, "r", "toe_off"), (19, "r", "heel_strike"), (24, "l", "toe_off")]


@pytest.mark.parametrize("label, context, expected", [
    ("Foot Strike", "Left", ("l", "heel_strike")), ("Foot Off", " right ", ("r", "toe_off")),
    ("LHS", "", ("l", "heel_strike")), ("RTO", "General", ("r", "toe_off")), ("R_FO", "", ("r", "toe_off")),
    ("Event", "General", None), ("General", "", None), ("Foot Strike", "General", None), ("Foot Off", "", None)])
def test_which_labels_are_gait_events(label, context, expected):
    assert gait_event(label, context) == expected


def test_a_file_without_an_event_group_has_no_events(tmp_path):
    rec, _ = _read(_file(tmp_path / "none.c3d"))
    assert len(rec.events) == 0


@pytest.mark.shared
def test_qualisys_events_match_its_event_group(shared_c3d_dir):
    path = shared_c3d_dir / "Qualisys.c3d"
    c = ezc3d.c3d(str(path))
    labels = c["parameters"]["EVENT"]["LABELS"]["value"]
    seconds = np.asarray(c["parameters"]["EVENT"]["TIMES"]["value"])[1]
    start = c["header"]["points"]["first_frame"] / c["parameters"]["POINT"]["RATE"]["value"][0]
    rec, _ = _read(path)
    assert len(rec.events) == len(labels) == 7
    for label, t in zip(labels, seconds):
        side, kind = label[0].lower(), {"HS": "heel_strike", "TO": "toe_off"}[label[1:]]
        assert np.abs(rec.events.times(side, kind) - (t - start)).min() < 1e-6
    assert {(s, k): int(rec.events.mask(s, k).sum()) for s in "rl" for k in ("heel_strike", "toe_off")} == {
        ("r", "heel_strike"): 2, ("r", "toe_off"): 2, ("l", "heel_strike"): 2, ("l", "toe_off"): 1}


def test_the_copy_carries_the_events_in_vicons_form(tmp_path):
    source = _file(tmp_path / "s.c3d", [(125, "Event", "General"), (130, "Foot Strike", "Left")])
    used = Events(np.array([2, 16, 39]), np.array([0.02, 0.16, 0.39]), np.array(["l", "r", "r"]),
                  np.array(["heel_strike", "toe_off", "heel_strike"]), np.array(["file", "plate", "kinematics"]))
    copy = add_points(source, tmp_path / "copy.c3d", {"X": np.zeros((N, 3))}, events=used)
    c = ezc3d.c3d(str(copy))
    group = c["parameters"]["EVENT"]
    assert group["USED"]["value"][0] == 3
    assert group["LABELS"]["value"] == ["Foot Strike", "Foot Off", "Foot Strike"]
    assert group["CONTEXTS"]["value"] == ["Left", "Right", "Right"]
    times = np.asarray(group["TIMES"]["value"])
    np.testing.assert_allclose(60 * times[0] + times[1], (np.array([103, 117, 140]) - 1) / RATE_HZ, rtol=1e-7)
    back, _ = _read(copy)  # and gait reads them back to the same frames
    assert back.events.frame.tolist() == [2, 16, 39] and set(back.events.source) == {"file"}
    np.testing.assert_allclose(back.events.time_s, used.time_s, atol=1e-9)
