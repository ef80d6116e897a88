"""Ceilings checked before reading (issue 35): a file that announces more than gaitcli reads is refused with
one line naming the file, the field and the ceiling, exit 2, before any data are read. The files are small:
they only claim to be huge."""

from __future__ import annotations

import ezc3d
import h5py
import numpy as np
import pytest

from gaitcli.core.recording import Markers
from gaitcli.errors import InputError
from gaitcli.io import tables
from gaitcli.io.c3d import read_c3d
from gaitcli.io.c3d.header import C3D_MAX_NUMBERS
from gaitcli.io.c3d.long import write_frame_count
from gaitcli.io.c3d_write import write_c3d
from gaitcli.io.h5 import H5_MAX_BYTES, _read_untyped
from tests.cli.conftest import MINIMAL_SUBJECT, gait, snapshot

CLAIMED_FRAMES = 2_000_000


@pytest.fixture
def claims_two_million_frames(tmp_path):
    """A trial folder whose trial.c3d holds 10 frames of 30 markers but says, as Vicon's long files do, 2 million
    (240 million numbers)."""
    trial = tmp_path / "long"
    trial.mkdir()
    positions = np.zeros((10, 30, 3)) + [0.1, 0.2, 0.3]
    labels = tuple(f"M{k}" for k in range(30))
    path = write_c3d(trial / "short.c3d", Markers(labels, positions, 100.0, first_frame=1), [])
    c = ezc3d.c3d(str(path))
    write_frame_count(c, CLAIMED_FRAMES)
    c.write(str(trial / "trial.c3d"))
    path.unlink()
    (trial / "subject.yaml").write_text(MINIMAL_SUBJECT)
    return trial


def test_a_c3d_above_the_ceiling_is_refused_before_reading(claims_two_million_frames):
    with pytest.raises(InputError) as caught:
        read_c3d(claims_two_million_frames / "trial.c3d")
    assert caught.value.field == "data"
    assert f"{CLAIMED_FRAMES} frames" in str(caught.value) and str(C3D_MAX_NUMBERS) in str(caught.value)


def test_gait_filter_exits_2_naming_the_c3d_ceiling(claims_two_million_frames, tmp_path):
    trial = claims_two_million_frames
    before = snapshot(trial)
    run = gait("filter", trial, "--no-plots", cwd=tmp_path, fresh=True)
    assert run.returncode == 2, run.describe()
    assert len(run.stderr_lines) == 1 and "trial.c3d" in run.stderr and str(C3D_MAX_NUMBERS) in run.stderr, \
        run.describe()
    assert snapshot(trial) == before


def test_predict_init_refuses_an_hdf5_that_expands_beyond_the_ceiling(tmp_path):
    """A few kB of HDF5 whose compressed, never written chunks claim 4.8 GB of design vector."""
    with h5py.File(tmp_path / "bomb.h5", "w") as h5:
        h5.create_dataset("result/design", shape=(600_000_000,), dtype="f8", chunks=(1 << 20,), compression="gzip")
    assert (tmp_path / "bomb.h5").stat().st_size < 100_000
    run = gait("predict", "--init", "bomb.h5", "--nodes", "6", "-o", "out", cwd=tmp_path, fresh=True)
    assert run.returncode == 2, run.describe()
    assert len(run.stderr_lines) == 1 and "bomb.h5" in run.stderr and "result/design" in run.stderr \
        and str(H5_MAX_BYTES) in run.stderr, run.describe()
    assert not (tmp_path / "out").exists()


def test_the_record_reader_checks_every_dataset(tmp_path):
    with h5py.File(tmp_path / "bomb.h5", "w") as h5:
        h5.create_dataset("result/x", shape=(80_000, 1000), dtype="f8", chunks=(1000, 1000), compression="gzip")
    with h5py.File(tmp_path / "bomb.h5", "r") as h5, pytest.raises(InputError, match="result/x"):
        _read_untyped(h5["result/x"])


def test_a_csv_beyond_its_cell_ceiling_is_refused_as_it_is_read(tmp_path, monkeypatch):
    monkeypatch.setattr(tables, "CSV_MAX_CELLS", 40)
    path = tmp_path / "markers.csv"
    path.write_text("time_s,A_x,A_y,A_z\n" + "".join(f"{k / 100},0,0,1\n" for k in range(20)))
    with pytest.raises(InputError, match="more than 10 rows of 4 columns") as caught:
        tables.read_markers_csv(path)
    assert "markers.csv" in str(caught.value) and "40 cells" in str(caught.value)
