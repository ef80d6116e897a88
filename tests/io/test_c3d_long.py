"""Trials longer than the C3D header's 65 535 frames (gaitcli/io/c3d/long.py): written with Vicon's TRIAL
fields, read whole (once cut to 65 535 without a word), through ezc3d part by part."""

from __future__ import annotations

import struct
import warnings

import ezc3d
import numpy as np
import pytest

from gaitcli.core.recording import ForcePlate, Markers
from gaitcli.errors import GaitWarning
from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d.long import HEADER_FRAMES, planned_frames
from gaitcli.io.c3d_write import write_c3d

FRAMES = HEADER_FRAMES + 4465  # 70 000: a second part of 4 465 frames
RATE_HZ = 100.0


@pytest.fixture(scope="module")
def long_trial(tmp_path_factory):
    """70 000 frames of three markers and one plate (analog at the marker rate) with known values."""
    t = np.arange(FRAMES) / RATE_HZ
    rng = np.random.default_rng(3)
    positions = np.stack([np.stack([np.sin(0.1 * t + k), np.cos(0.2 * t), 0.5 + 0.01 * k + 0 * t], axis=1)
                          for k in range(3)], axis=1) + rng.normal(0, 1e-3, (FRAMES, 3, 3))
    positions[FRAMES - 10:FRAMES - 5, 1] = np.nan  # missing samples in the second part stay missing
    markers = Markers(("A", "B", "C"), positions, RATE_HZ, first_frame=1)
    corners = np.array([[0.25, -0.2, 0], [-0.25, -0.2, 0], [-0.25, 0.2, 0], [0.25, 0.2, 0]])
    force = np.stack([10 * np.sin(t), 5 * np.cos(t), 600 + 100 * np.sin(0.5 * t)], axis=1)
    moment = np.stack([2 * np.cos(t), -3 * np.sin(t), np.sin(3 * t)], axis=1)
    plate = ForcePlate("plate1", force, moment, corners.mean(axis=0), corners, RATE_HZ)
    path = write_c3d(tmp_path_factory.mktemp("long") / "long.c3d", markers, [plate])
    return path, markers, plate


def test_the_written_file_says_how_long_it_is(long_trial):
    path, _, _ = long_trial
    c = ezc3d.c3d(str(path))
    assert c["data"]["points"].shape[2] == HEADER_FRAMES  # what the library alone reads
    trial = c["parameters"]["TRIAL"]
    start, end = trial["ACTUAL_START_FIELD"]["value"], trial["ACTUAL_END_FIELD"]["value"]
    assert (int(start[0]), int(start[1])) == (1, 0)
    assert (int(end[0]) & 0xFFFF) | (int(end[1]) << 16) == FRAMES


def test_every_frame_and_sample_is_read_back(long_trial):
    path, markers, plate = long_trial
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        recording = read_c3d(path, to_model_axes=False)
    assert recording.markers.n_frames == FRAMES and recording.plates[0].n_samples == FRAMES
    np.testing.assert_array_equal(np.isnan(recording.markers.positions_m), np.isnan(markers.positions_m))
    assert np.nanmax(np.abs(recording.markers.positions_m - markers.positions_m)) < 1e-6  # float32 mm
    np.testing.assert_allclose(recording.plates[0].force_N, plate.force_N, atol=1e-3)
    np.testing.assert_allclose(recording.plates[0].moment_Nm, plate.moment_Nm, atol=1e-3)
    assert any("read in parts" in note for note in recording.notes)


@pytest.mark.parametrize("params,expected", [
    ({"TRIAL": {"ACTUAL_START_FIELD": [1, 0], "ACTUAL_END_FIELD": [4464, 1]}}, 70000),
    ({"TRIAL": {"ACTUAL_START_FIELD": [1, 0], "ACTUAL_END_FIELD": [-1, 1]}}, 131071),  # a signed low word
    ({"POINT": {"LONG_FRAMES": [80000.0]}}, 80000),
    ({"POINT": {"LONG_FRAMES": [100.0]}}, 300),  # fewer than the header's: the header's
    ({}, 300),
])
def test_the_frame_count_is_read_from_the_bytes_before_the_data(tmp_path, params, expected):
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c["parameters"]["POINT"]["LABELS"]["value"] = ["A", "B"]
    c["data"]["points"] = np.ones((4, 2, 300))
    for group, values in params.items():
        for name, value in values.items():
            c.add_parameter(group, name, value)
    c.write(str(tmp_path / "t.c3d"))
    assert planned_frames(tmp_path / "t.c3d") == (expected, 8)


@pytest.mark.parametrize("part_numbers", [6500, 2 * 10**6])
def test_a_trial_read_in_parts_equals_the_trial_read_whole(long_trial, monkeypatch, part_numbers):
    """Parts of 500 and (for the 70 000 frames) 65 535 frames: the same markers, plates and notes, the
    FORCE_PLATFORM baseline taken once over the file's own frames."""
    import gaitcli.io.c3d as reader

    path, _, _ = long_trial
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        whole = read_c3d(path, to_model_axes=False)
        monkeypatch.setattr(reader, "PART_NUMBERS", part_numbers)
        parts = reader.read_c3d_here(path, to_model_axes=False)
    assert parts.markers.labels == whole.markers.labels and parts.markers.first_frame == whole.markers.first_frame
    np.testing.assert_array_equal(parts.markers.positions_m, whole.markers.positions_m)
    for a, b in zip(parts.plates, whole.plates, strict=True):
        np.testing.assert_array_equal(a.force_N, b.force_N)
        np.testing.assert_array_equal(a.moment_Nm, b.moment_Nm)
    assert [n for n in parts.notes if "read in parts" not in n] == [n for n in whole.notes if "read in parts" not in n]


def test_a_long_file_whose_data_are_cut_is_refused(long_trial, tmp_path):
    from gaitcli.errors import InputError

    path, _, _ = long_trial
    cut = tmp_path / "cut.c3d"
    cut.write_bytes(path.read_bytes()[:-4096])
    with pytest.raises(InputError, match="truncated"):
        read_c3d(cut)
    assert struct.unpack("<H", path.read_bytes()[8:10])[0] <= HEADER_FRAMES
