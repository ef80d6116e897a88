"""C3D file and header checks, and access to the parameter section.

The 512-byte header and the start of the parameter section are validated
before ezc3d opens the file (a cut parameter section makes ezc3d hang):
missing or non-C3D files, MIPS/SGI processor format, truncated parameter or
data sections and a data section above :data:`C3D_MAX_NUMBERS` are :class:`~gaitcli.errors.InputError`s of
one line.
"""

from __future__ import annotations

import math
import os
import struct
import warnings
from dataclasses import dataclass
from pathlib import Path

from gaitcli.errors import GaitWarning, InputError

__all__ = ["C3D_MAX_NUMBERS", "check_file", "check_parameters", "data_layout", "one_line", "warn", "param", "strings",
           "as_text"]

_MIPS_MESSAGE = (
    "cannot read C3D: MIPS/SGI processor format is not supported; expected Intel or DEC (re-export the file)"
)


def one_line(exc: BaseException) -> str:
    """An exception's text on one line (ezc3d's messages span several)."""
    text = " ".join(str(exc).split())
    return text.removesuffix(": iostream error") or type(exc).__name__


def check_file(path: Path) -> int | None:
    """Validate the header before ezc3d sees the file (a cut parameter section makes ezc3d hang).

    Returns the frame count the header announces (None when its 16-bit frame
    numbers cannot be trusted).
    """
    if not path.exists():
        raise InputError(path, None, "file not found")
    if not path.is_file():
        raise InputError(path, None, "not a file (expected a C3D file)")
    size = path.stat().st_size
    if not os.access(path, os.R_OK):
        raise InputError(path, None, "cannot be read (permission denied)")
    with open(path, "rb") as f:
        head = f.read(512)
        if size < 512:
            raise InputError(path, "header", f"not a C3D file: {size} bytes, shorter than the 512-byte header")
        if head.startswith(b"%PDF-"):
            raise InputError(path, "header", "not a C3D file: it is a PDF document")
        if head[1] != 0x50:
            raise InputError(path, "header", f"not a C3D file: byte 2 is 0x{head[1]:02X}, expected 0x50")
        param_block = head[0]
        if param_block < 2:
            raise InputError(path, "header", f"not a C3D file: parameter block number {param_block} (expected >= 2)")
        param_offset = (param_block - 1) * 512
        f.seek(param_offset)
        param_head = f.read(4)
    if len(param_head) < 4:
        raise InputError(path, "parameters", f"cannot read C3D: file is truncated ({size} bytes, no parameter section)")
    processor = param_head[3] - 83
    if processor == 3:
        raise InputError(path, "processor", _MIPS_MESSAGE)
    if processor not in (1, 2):
        raise InputError(
            path, "processor", f"not a C3D file: processor byte {param_head[3]} (expected 84 Intel or 85 DEC)"
        )
    n_param_blocks = param_head[2]
    if size < param_offset + 512 * n_param_blocks:
        raise InputError(
            path, "parameters",
            f"cannot read C3D: file is truncated ({size} bytes, the parameter section needs "
            f"{param_offset + 512 * n_param_blocks})",
        )
    records = check_parameters(path, param_offset, n_param_blocks, size)
    first, last = struct.unpack("<2H", head[6:10])
    data_start, frame_bytes = data_layout(head, processor)
    check_ceiling(path, head, records, processor)
    check_rates(path, head, records, processor)
    if data_start < param_block * 512:
        raise InputError(path, "header", f"not a C3D file: data block {data_start // 512 + 1} is not after the "
                                         "parameters")
    if last < first:
        return None
    n_frames = last - first + 1
    need = data_start + n_frames * frame_bytes
    if size < need:
        raise InputError(
            path, "data",
            f"cannot read C3D: file is truncated ({size} bytes, the header's {n_frames} frames need {need})",
        )
    return n_frames


#: the most numbers a C3D data section may hold for gaitcli to read it: frames × (4 per marker + analog
#: channels × analog samples per frame). 10 minutes at 100 Hz of 60 markers and two 1 kHz plates of 8 channels
#: are 24 million; the C3D library takes ~130 bytes of memory per number, so the ceiling keeps a read under ~5 GB
C3D_MAX_NUMBERS = 40_000_000


def check_ceiling(path: Path, head: bytes, records: dict, processor: int) -> None:
    """Refuse a file whose data section announces more than :data:`C3D_MAX_NUMBERS` numbers, from the header
    and the long-trial frame counts (TRIAL:ACTUAL_START/END_FIELD, POINT:FRAMES, POINT:LONG_FRAMES), before
    any data are read."""
    n_points, analog_per_frame = struct.unpack("<2H", head[2:6])
    first, last = struct.unpack("<2H", head[6:10])
    frames = max(last - first + 1, *long_frame_counts(path, records, processor), 0)
    per_frame = 4 * n_points + analog_per_frame
    if frames * per_frame > C3D_MAX_NUMBERS:
        raise InputError(path, "data", f"{frames} frames of {n_points} markers and {analog_per_frame} analog "
                                       f"samples each: {frames * per_frame} numbers, more than gaitcli reads "
                                       f"({C3D_MAX_NUMBERS}; split the trial)")


def _floats(raw: bytes, processor: int) -> list[float]:
    """4-byte floats of the file's processor: Intel IEEE, or DEC F-float (IEEE with its 16-bit words swapped,
    four times as large)."""
    raw = raw[:len(raw) // 4 * 4]
    if processor == 2:
        raw = b"".join(raw[k + 2:k + 4] + raw[k:k + 2] for k in range(0, len(raw), 4))
        return [v / 4 for (v,) in struct.iter_unpack("<f", raw)]
    return [v for (v,) in struct.iter_unpack("<f", raw)]


def parameter_numbers(path: Path, records: dict, processor: int, group: str, name: str,
                      count: int = 2) -> list[float]:
    """The first ``count`` values of the numeric parameter GROUP:NAME read from the file's bytes ([] when absent or
    not a 16-bit integer or a float; 16-bit words as unsigned)."""
    record = records.get((group, name))
    if record is None or record.kind not in (2, 4):
        return []
    count = max(1, min(count, record.dims[0] if record.dims else 1))
    with open(path, "rb") as f:
        f.seek(record.data_offset)
        raw = f.read(4 * count)
    if record.kind == 2:
        return [float(w) for (w,) in struct.iter_unpack("<H", raw[:2 * count])]
    return _floats(raw[:4 * count], processor)


def check_rates(path: Path, head: bytes, records: dict, processor: int) -> None:
    """Refuse parameters that disagree with the header that lays out the data section: POINT:USED against its
    points per frame, POINT:RATE against the
    header's frame rate, ANALOG:RATE against its analog samples per frame at that rate, POINT:SCALE's sign
    against its storage (floats or integers) and, for integers, its size against the header's scale. Read
    either way, such a file gives markers and plates from the wrong bytes."""
    n_points, analog_per_frame = struct.unpack("<2H", head[2:6])
    scale, rate = _floats(head[12:16], processor)[0], _floats(head[20:24], processor)[0]

    def refuse(field: str, got: float, expected: str):
        raise InputError(path, field, f"got {got:g} ({expected}; the parameters or the header are damaged)")

    if not (math.isfinite(rate) and rate > 0):
        raise InputError(path, "header", f"frame rate {rate:g} Hz (expected a positive rate; the header is damaged)")
    point_used = parameter_numbers(path, records, processor, "POINT", "USED", 1)
    if point_used and int(point_used[0]) != n_points:
        refuse("POINT:USED", point_used[0], f"expected the header's {n_points} points per frame")
    point_rate = parameter_numbers(path, records, processor, "POINT", "RATE", 1)
    if point_rate and not math.isclose(point_rate[0], rate, rel_tol=1e-3):
        refuse("POINT:RATE", point_rate[0], f"expected the header's {rate:g} Hz")
    point_scale = parameter_numbers(path, records, processor, "POINT", "SCALE", 1)
    if n_points and point_scale:
        # its sign says how the data are stored (negative: floats, its size unused; positive: integers times it)
        if (point_scale[0] < 0) != (scale < 0):
            refuse("POINT:SCALE", point_scale[0], f"expected {'a negative' if scale < 0 else 'a positive'} scale: "
                                                   f"the header stores the data as "
                                                   f"{'floats' if scale < 0 else 'integers'} ({scale:g})")
        if scale > 0 and not math.isclose(point_scale[0], scale, rel_tol=1e-5):
            refuse("POINT:SCALE", point_scale[0], f"expected the header's {scale:g}")
    used = parameter_numbers(path, records, processor, "ANALOG", "USED", 1)
    analog_rate = parameter_numbers(path, records, processor, "ANALOG", "RATE", 1)
    if analog_per_frame and used and used[0] > 0 and analog_rate:
        per_channel = analog_per_frame / used[0]
        if per_channel != int(per_channel):
            refuse("ANALOG:USED", used[0], f"expected a divisor of the header's {analog_per_frame} analog samples "
                                           "per frame")
        expected = per_channel * rate
        if not math.isclose(analog_rate[0], expected, rel_tol=1e-4):
            refuse("ANALOG:RATE", analog_rate[0], f"expected {expected:g} Hz: the header's {int(per_channel)} samples "
                                                  f"per frame at {rate:g} Hz")


def long_frame_counts(path: Path, records: dict, processor: int) -> list[int]:
    """The frame counts a long trial's parameters announce (see :mod:`.long`), read from the file's bytes."""
    def values(group, name):
        return [int(v) for v in parameter_numbers(path, records, processor, group, name)
                if v == v and abs(v) < 2**40]

    counts = []
    start, end = values("TRIAL", "ACTUAL_START_FIELD"), values("TRIAL", "ACTUAL_END_FIELD")
    if len(start) == 2 and len(end) == 2:
        low_high = [[w & 0xFFFF for w in words] for words in (start, end)]  # words maybe stored signed
        counts.append((low_high[1][0] | low_high[1][1] << 16) - (low_high[0][0] | low_high[0][1] << 16) + 1)
    for name in ("LONG_FRAMES", "FRAMES"):
        counts += values("POINT", name)[:1]
    return counts


#: parameter types (C3D: −1 text, 1 byte, 2 16-bit integer, 4 float) and the most dimensions a parameter has
_TYPES = (-1, 1, 2, 4)
_MAX_DIMENSIONS = 7


def check_parameters(path: Path, offset: int, blocks: int, size: int) -> dict:
    """Walk the parameter section's records the way a reader does and check each one lies inside it.

    A record: name length n (int8; < 0 locked, 0 ends the section), group/parameter id (int8; < 0 a group),
    the name, the offset to the next record (int16, from its own position; 0 the last), then for a group a
    description, for a parameter its type, dimensions, data and description. Refused before the C3D library
    reads them: a record or its data past the section's end, an offset that does not move forward, an unknown
    type, more than 7 dimensions, a parameter of a group that does not exist. One corrupted byte here once
    made the library crash, hang, or allocate 12.7 GB for a 0.5 MB file. Returns (GROUP, NAME) →
    :class:`ParameterRecord`.
    """
    end = offset + 512 * blocks
    if blocks == 0:
        raise InputError(path, "parameters", "parameter section damaged: it holds 0 blocks")
    with open(path, "rb") as f:
        f.seek(offset)
        section = f.read(512 * blocks)
    if len(section) < 512 * blocks or end > size:
        raise InputError(path, "parameters", f"cannot read C3D: file is truncated ({size} bytes, the parameter "
                                             f"section needs {end})")
    groups, members, names, records = set(), [], {}, {}
    at = 4
    while True:
        where = offset + at

        def damaged(problem: str, where: int = where):
            return InputError(path, "parameters", f"parameter section damaged at byte {where}: {problem}")

        if at + 2 > len(section):
            raise damaged("a record runs past the section's end")
        n_chars, ident = struct.unpack("<bb", section[at:at + 2])
        if n_chars == 0:
            break
        name_end = at + 2 + abs(n_chars)
        if name_end + 2 > len(section):
            raise damaged("a record's name runs past the section's end")
        (next_offset,) = struct.unpack("<h", section[name_end:name_end + 2])
        body = name_end + 2
        name = section[at + 2:name_end].decode("latin-1").upper()
        if ident < 0:
            groups.add(-ident)
            names[-ident] = name
            fields_end = body + 1 + (section[body] if body < len(section) else 0)
        else:
            if body + 2 > len(section):
                raise damaged("a parameter's type runs past the section's end")
            kind, n_dims = struct.unpack("<bB", section[body:body + 2])
            if kind not in _TYPES:
                raise damaged(f"parameter type {kind} (expected -1, 1, 2 or 4)")
            if n_dims > _MAX_DIMENSIONS:
                raise damaged(f"{n_dims} dimensions (expected at most {_MAX_DIMENSIONS})")
            dims = section[body + 2:body + 2 + n_dims]
            if len(dims) < n_dims:
                raise damaged("a parameter's dimensions run past the section's end")
            count = 1
            for d in dims:
                count *= d
            data_end = body + 2 + n_dims + count * abs(kind)
            if data_end >= len(section):
                raise damaged(f"a parameter's {count * abs(kind)} bytes of data run past the section's end")
            fields_end = data_end + 1 + section[data_end]
            members.append((ident, where))
            records[(ident, name)] = ParameterRecord(kind, tuple(dims), offset + body + 2 + n_dims)
        if fields_end > len(section):
            raise damaged("a description runs past the section's end")
        if next_offset == 0:
            break
        following = name_end + next_offset
        if next_offset < 0 or following < fields_end - 1 or following <= at:
            raise damaged(f"offset {next_offset} to the next record does not move past this one")
        if following >= len(section):
            break  # the section ends without a terminating record
        at = following
    for ident, where in members:
        if ident not in groups:
            raise InputError(path, "parameters", f"parameter section damaged at byte {where}: a parameter of "
                                                 f"group {ident}, which the section does not define")
    return {(names[ident], name): record for (ident, name), record in records.items()}


@dataclass(frozen=True)
class ParameterRecord:
    """Where one parameter's data lie in the file: type (−1, 1, 2, 4), dimensions, byte offset of the data."""

    kind: int
    dims: tuple[int, ...]
    data_offset: int


def data_layout(head: bytes, processor: int) -> tuple[int, int]:
    """(byte offset of the data section, bytes per frame) from the 512-byte header; ``processor`` 1 Intel,
    2 DEC (the parameter section's processor byte − 83)."""
    n_points, analog_per_frame = struct.unpack("<2H", head[2:6])
    data_block = struct.unpack("<H", head[16:18])[0]
    if processor == 1:
        is_float = struct.unpack("<f", head[12:16])[0] < 0
    else:  # DEC F-float: the sign bit is the top bit of the first 16-bit word
        is_float = bool(head[13] & 0x80)
    return (data_block - 1) * 512, (4 * n_points + analog_per_frame) * (4 if is_float else 2)


def warn(message: str, notes: list[str]) -> None:
    """Note ``message`` and warn it as a :class:`GaitWarning` attributed to the reader's caller."""
    notes.append(message)
    warnings.warn(message, GaitWarning, stacklevel=3)


# ------------------------------------------------------------------ parameters


def param(params, group: str, name: str, default=None):
    """The value of parameter GROUP:NAME, or ``default`` where it is absent."""
    try:
        return params[group][name]["value"]
    except KeyError:
        return default


def strings(params, group: str, name: str) -> list[str]:
    """A CHAR parameter and its continuations (NAME2, NAME3, ...) as one list."""
    out = list(param(params, group, name, []) or [])
    k = 2
    while param(params, group, f"{name}{k}") is not None:
        out += list(param(params, group, f"{name}{k}"))
        k += 1
    return [as_text(s) for s in out]


def as_text(value) -> str:
    """A C3D string as text: ezc3d hands bytes that are not UTF-8 over as surrogate escapes (e.g. a Latin-1
    'é' as '\\udce9'), which no file can be written with; those strings are read as Latin-1."""
    text = str(value)
    try:
        text.encode("utf-8")
        return text
    except UnicodeEncodeError:
        raw = text.encode("utf-8", "surrogateescape")
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError:
            return raw.decode("latin-1")
