"""Trials read in parts: longer than the C3D header's 65 535 frames (ezc3d reads no more), or too large for the
library's per-sample objects to hold at once.

Long files say how long they are in TRIAL:ACTUAL_START_FIELD / ACTUAL_END_FIELD (two 16-bit words each, low
word first: Vicon) or in POINT:FRAMES stored as a float (the C3D specification's advice); POINT:LONG_FRAMES
(a float) is read too. :func:`planned_frames` reads them from the file's bytes; :func:`chunk_files` writes a
stretch of frames as a short C3D file at a time, the original's header and parameters with the frame range,
the data start and the frame count rewritten and that stretch of data behind them, so that ezc3d (and its
force-platform module) reads every part as it reads any file. :func:`write_frame_count` marks a long file
gaitcli writes the way Vicon does.
"""
from __future__ import annotations

import struct
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from gaitcli.errors import InputError
from gaitcli.io.c3d.header import ParameterRecord, check_parameters, data_layout, long_frame_counts

#: the most frames a C3D header (and ezc3d) counts
HEADER_FRAMES = 65535


def planned_frames(path: Path) -> tuple[int | None, int]:
    """(frames, numbers per frame) of the C3D file ``path`` from its header and parameter bytes, before any data
    are read: the header's count, or more where the long-trial fields say so (TRIAL:ACTUAL_START/END_FIELD,
    POINT:LONG_FRAMES, a float POINT:FRAMES); frames None where the header's 16-bit frame numbers run
    backwards (the library then decides)."""
    with open(path, "rb") as f:
        head = f.read(512)
        f.seek((head[0] - 1) * 512)
        param_head = f.read(4)
    processor = param_head[3] - 83
    records = check_parameters(path, (head[0] - 1) * 512, param_head[2], path.stat().st_size)
    n_points, analog_per_frame = struct.unpack("<2H", head[2:6])
    first, last = struct.unpack("<2H", head[6:10])
    if last < first:
        return None, 4 * n_points + analog_per_frame
    return max(last - first + 1, *long_frame_counts(path, records, processor)), 4 * n_points + analog_per_frame


@contextmanager
def chunk_files(path: Path, total_frames: int, part_frames: int = HEADER_FRAMES, *,
                start_frame: int = HEADER_FRAMES) -> Iterator[Iterator[tuple[Path, int]]]:
    """Temporary C3D files of frames ``start_frame`` + 1 … ``total_frames`` of ``path`` (counted from 1), at
    most ``part_frames`` (≤ 65 535) each, made one at a time: yields an iterator of (file, frames), each file
    removed once the next is asked for, the last on leaving."""
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

    def parts(folder: str) -> Iterator[tuple[Path, int]]:
        with open(path, "rb") as f:
            for first in range(start_frame, total_frames, part_frames):
                count = min(part_frames, total_frames - first)
                part = bytearray(head)
                part[6:10] = struct.pack("<2H", 1, count)  # first and last frame
                part[16:18] = struct.pack("<H", new_block)
                _set(part, records.get(("POINT", "DATA_START")), new_block)
                _set(part, records.get(("POINT", "FRAMES")), count)
                _set(part, records.get(("POINT", "LONG_FRAMES")), count)
                _set(part, records.get(("TRIAL", "ACTUAL_START_FIELD")), 1)
                _set(part, records.get(("TRIAL", "ACTUAL_END_FIELD")), count)
                f.seek(start + first * frame_bytes)
                chunk = Path(folder) / "part.c3d"
                chunk.write_bytes(bytes(part) + f.read(count * frame_bytes))  # one part's data at a time
                yield chunk, count

    with tempfile.TemporaryDirectory(prefix="gait-c3d-") as folder:
        yield parts(folder)


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
