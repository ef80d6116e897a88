"""Trials longer than 65 535 frames: the C3D header counts frames in 16 bits, and ezc3d reads no more.

Such files say how long they are in TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD (two 16-bit words each, low
word first: Vicon) or in POINT:FRAMES stored as a float (the C3D specification's advice); POINT:LONG_FRAMES
(a float) is read too. :func:`frame_count` reads them; :func:`chunk_files` writes the frames beyond the
first 65 535 as short C3D files, each the original's header and parameters with the frame range, the data
start and the frame count rewritten and the next stretch of data behind them, so that ezc3d (and its
force-platform module) reads every part as it reads any file. FORCE_PLATFORM:ZERO is then applied per part,
over that part's own frames. :func:`write_frame_count` marks a long file gaitcli writes the way Vicon does.
"""

from __future__ import annotations

import struct
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from gaitcli.errors import InputError
from gaitcli.io.c3d.header import ParameterRecord, check_parameters, data_layout, param

#: the most frames a C3D header (and ezc3d) counts
HEADER_FRAMES = 65535


def _words(value) -> int | None:
    """A 32-bit count from two 16-bit words (low first), each maybe stored as a signed int16."""
    words = np.asarray(value, dtype=float).ravel()
    if words.size < 2 or not np.all(np.isfinite(words)):
        return None
    low, high = (int(w) & 0xFFFF for w in words[:2])
    return low | (high << 16)


def frame_count(params, frames_read: int) -> int:
    """The trial's frame count: the TRIAL fields', POINT:LONG_FRAMES' or a float POINT:FRAMES' where they say
    more than ``frames_read`` (what ezc3d read), else ``frames_read``."""
    start, end = _words(param(params, "TRIAL", "ACTUAL_START_FIELD")), _words(param(params, "TRIAL",
                                                                                   "ACTUAL_END_FIELD"))
    counts = [end - start + 1] if start is not None and end is not None and end >= start else []
    for name in ("LONG_FRAMES", "FRAMES"):
        value = np.asarray(param(params, "POINT", name, []), dtype=float).ravel()
        if value.size and np.isfinite(value[0]):
            counts.append(int(value[0]))
    longer = [n for n in counts if n > frames_read]
    return max(longer) if longer else frames_read


@contextmanager
def chunk_files(path: Path, total_frames: int) -> Iterator[list[tuple[Path, int]]]:
    """Temporary C3D files of frames 65 536 … ``total_frames`` of ``path``, at most 65 535 frames each; yields
    [(file, frames)] and removes them afterwards."""
    size = path.stat().st_size
    with open(path, "rb") as f:
        head = f.read(512)
        param_block = head[0]
        offset = (param_block - 1) * 512
        f.seek(offset)
        param_head = f.read(4)
        blocks = param_head[2]
        f.seek(0)
        head = bytearray(f.read(offset + 512 * blocks))  # header and parameters, copied into every part
    records = check_parameters(path, offset, blocks, size)
    start, frame_bytes = data_layout(head, param_head[3] - 83)
    if start + total_frames * frame_bytes > size:
        raise InputError(path, "data", f"cannot read C3D: file is truncated ({size} bytes, its "
                                       f"{total_frames} frames need {start + total_frames * frame_bytes})")
    new_block = param_block + blocks  # the data right after the parameters
    with tempfile.TemporaryDirectory(prefix="gait-c3d-") as folder, open(path, "rb") as f:
        out = []
        for k, first in enumerate(range(HEADER_FRAMES, total_frames, HEADER_FRAMES)):
            count = min(HEADER_FRAMES, total_frames - first)
            part = bytearray(head)
            part[6:10] = struct.pack("<2H", 1, count)  # first and last frame
            part[16:18] = struct.pack("<H", new_block)
            _set(part, records.get(("POINT", "DATA_START")), new_block)
            _set(part, records.get(("POINT", "FRAMES")), count)
            _set(part, records.get(("POINT", "LONG_FRAMES")), count)
            _set(part, records.get(("TRIAL", "ACTUAL_START_FIELD")), 1)
            _set(part, records.get(("TRIAL", "ACTUAL_END_FIELD")), count)
            f.seek(start + first * frame_bytes)
            chunk = Path(folder) / f"part{k + 1}.c3d"
            chunk.write_bytes(bytes(part) + f.read(count * frame_bytes))  # one part's data at a time
            out.append((chunk, count))
        yield out


def _set(section: bytearray, record: ParameterRecord | None, value: int) -> None:
    """Overwrite a numeric parameter's first value (16-bit words as an unsigned count, low word first)."""
    if record is None:
        return
    at = record.data_offset
    if record.kind == 4:
        section[at:at + 4] = struct.pack("<f", float(value))
    elif record.kind == 2:
        section[at:at + 2] = struct.pack("<H", value & 0xFFFF)
        if record.dims and record.dims[0] >= 2:
            section[at + 2:at + 4] = struct.pack("<H", value >> 16)


def write_frame_count(c, n_frames: int) -> None:
    """Mark an ezc3d object of more than 65 535 frames as Vicon does: TRIAL:ACTUAL_START_FIELD = 1 and
    ACTUAL_END_FIELD = n (two 16-bit words, low first, as signed int16 values)."""
    if n_frames <= HEADER_FRAMES:
        return

    def signed(word: int) -> int:
        return word - 0x10000 if word > 0x7FFF else word

    c.add_parameter("TRIAL", "ACTUAL_START_FIELD", [1, 0])
    c.add_parameter("TRIAL", "ACTUAL_END_FIELD", [signed(n_frames & 0xFFFF), n_frames >> 16])
