"""Damaged C3D files (issue 9): seeded single-byte mutations of the header and the parameter section of a
sample trial and of c3d.org's Eb015pi.c3d (integer storage, another writer), each read by ``read_c3d``. Every
read must end in a recording or a one-line InputError, within its time limit: no crash (once a segfault of the
C3D library killed gait), no hang, no runaway allocation (once 12.7 GB for a 0.5 MB file), no other exception."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from gaitcli.core.recording import Recording
from gaitcli.errors import InputError
from gaitcli.io.c3d import read_c3d
from gaitcli.resources import sample_trial

from ..conftest import SHARED_C3D

MUTATIONS = {"sample": 60, "lab": 140}  # 200 in all; the lab file's part skips without ../shared
CHUNKS = 4  # tests per file, so that pytest-xdist shares the reads out
LIMIT_S = 10.0


def _mutations(source: Path, seed: int, count: int) -> list[tuple[int, int]]:
    """(byte offset, new value) pairs inside the header and the parameter section, seeded."""
    data = source.read_bytes()
    end = (data[0] - 1) * 512 + 512 * data[(data[0] - 1) * 512 + 2]
    rng = np.random.default_rng(seed)
    offsets = rng.integers(0, min(end, len(data)), count)
    values = [(int(data[o]) + int(rng.integers(1, 256))) % 256 for o in offsets]
    return list(zip(map(int, offsets), values))


def _read_mutated(source: Path, tmp_path: Path, seed: int, count: int, chunk: int, monkeypatch) -> dict:
    import gaitcli.io.c3d as c3d_module

    data = bytearray(source.read_bytes())
    # the bounds exactly: 10 s and 1 GB per read (the reader's limits grow with the file's size)
    monkeypatch.setattr(c3d_module, "READ_TIME_S", LIMIT_S - len(data) / 1e6)
    monkeypatch.setattr(c3d_module, "READ_MEMORY_BYTES", (1 << 30) - c3d_module.READ_BYTES_PER_BYTE * len(data))
    outcomes = {"read": 0, "refused": 0}
    for offset, value in _mutations(source, seed, count)[chunk::CHUNKS]:
        mutated = bytearray(data)
        mutated[offset] = value
        path = tmp_path / f"mutated_{offset}_{value}.c3d"
        path.write_bytes(bytes(mutated))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                recording = read_c3d(path)
            assert isinstance(recording, Recording)
            outcomes["read"] += 1
        except InputError as exc:
            message = str(exc)
            assert "\n" not in message and len(message) < 400 and str(path) in message, message
            assert "ignoreBadFormatting" not in message, message  # the library's advice, not gait's
            outcomes["refused"] += 1
        path.unlink()
    return outcomes


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_sample_trial(tmp_path, chunk, monkeypatch):
    outcomes = _read_mutated(sample_trial("normal") / "trial.c3d", tmp_path, seed=9, count=MUTATIONS["sample"],
                             chunk=chunk, monkeypatch=monkeypatch)
    assert sum(outcomes.values()) == len(range(chunk, MUTATIONS["sample"], CHUNKS))


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_lab_file(tmp_path, chunk, monkeypatch):
    if not SHARED_C3D.is_dir():
        pytest.skip("../shared/data/c3d is absent")
    outcomes = _read_mutated(SHARED_C3D / "Eb015pi.c3d", tmp_path, seed=10, count=MUTATIONS["lab"], chunk=chunk,
                             monkeypatch=monkeypatch)
    assert sum(outcomes.values()) == len(range(chunk, MUTATIONS["lab"], CHUNKS))
