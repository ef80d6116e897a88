"""The analog channels that are no force plate's (EMG): a written file read back whole and in parts, the plates'
channels left out, and the two real trials with raw EMG (skipped where ../shared is absent)."""

from __future__ import annotations

import warnings

import ezc3d
import numpy as np
import pytest

from gaitcli.errors import GaitWarning
from gaitcli.io.c3d import read_c3d

from ..conftest import REPO, SHARED_C3D

SHARED_EMG = REPO.parent / "shared" / "data" / "emg"
FRAMES = 120


@pytest.fixture
def emg_trial(tmp_path):
    """A C3D of 3 markers at 100 Hz and two EMG channels at 1 kHz, labels and units as two labs write them;
    (path, values (channels × samples))."""
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [100]
    c["parameters"]["POINT"]["LABELS"]["value"] = ("M1", "M2", "M3")
    c["parameters"]["POINT"]["UNITS"]["value"] = ["m"]
    points = np.ones((4, 3, FRAMES))
    points[:3] = np.random.default_rng(0).normal(size=(3, 3, FRAMES))
    c["data"]["points"] = points
    c["parameters"]["ANALOG"]["RATE"]["value"] = [1000]
    c["parameters"]["ANALOG"]["LABELS"]["value"] = ("RTIBA", "Voltage.RGAS")
    c["parameters"]["ANALOG"]["UNITS"]["value"] = ("V", "mV")
    t = np.arange(FRAMES * 10) / 1000.0
    values = np.vstack([np.sin(2 * np.pi * 50 * t), 0.5 * np.cos(2 * np.pi * 80 * t) + 0.1])
    c["data"]["analogs"] = values[None]
    path = tmp_path / "emg.c3d"
    c.write(str(path))
    return path, values


def _read(path, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)  # no plates: markers only
        return read_c3d(path, **kwargs)


def test_emg_channels_are_read_with_their_labels_units_and_rate(emg_trial):
    path, values = emg_trial
    analogs = _read(path).analogs
    assert analogs.labels == ("RTIBA", "Voltage.RGAS") and analogs.units == ("V", "mV")
    assert analogs.rate_hz == 1000.0 and analogs.n_samples == FRAMES * 10
    np.testing.assert_allclose(analogs.values, values.T, atol=1e-6)  # stored as 32-bit floats


def test_emg_channels_read_in_parts_equal_them_read_whole(emg_trial, monkeypatch):
    import gaitcli.io.c3d as reader

    path, values = emg_trial
    whole = _read(path).analogs
    monkeypatch.setattr(reader, "PART_NUMBERS", 100)  # parts of 25 frames
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", GaitWarning)
        parts = reader.read_c3d_here(path)
    assert any("read in parts" in n for n in parts.notes)
    assert parts.analogs.labels == whole.labels and parts.analogs.units == whole.units
    np.testing.assert_array_equal(parts.analogs.values, whole.values)


def test_a_trial_whose_analogs_are_all_its_plates_has_none_left():
    analogs = _read(REPO / "sample_trials" / "normal" / "trial.c3d").analogs
    assert analogs is None


def test_the_real_trials_emg_channels():
    if not (SHARED_C3D / "BTS.c3d").is_file() or not (SHARED_EMG / "Gait.c3d").is_file():
        pytest.skip("../shared/data (c3d/BTS.c3d, emg/Gait.c3d) is not present next to this checkout")
    bts = _read(SHARED_C3D / "BTS.c3d").analogs  # 36 plate channels, then 8 EMG in mV
    assert bts.labels[4:6] == ("Left Tibialis anterior", "Right Tibialis anterior") and len(bts.labels) == 8
    assert set(bts.units) == {"mV"} and bts.rate_hz == 1000.0 and bts.n_samples == 6750
    gait = _read(SHARED_EMG / "Gait.c3d").analogs  # 16 channels in V, rectus femoris clipped at ±1 V
    assert len(gait.labels) == 16 and gait.labels[:2] == ("LREC", "RREC") and set(gait.units) == {"V"}
    assert np.abs(gait.values[:, :2]).max() == pytest.approx(1.0, abs=1e-3)
    assert abs(np.mean(gait.values[:, 1])) > 0.2  # RREC's DC offset, as README.md says
