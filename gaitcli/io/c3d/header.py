"""C3D file and header checks, and access to the parameter section.

The 512-byte header and the start of the parameter section are validated
before ezc3d opens the file (a cut parameter section makes ezc3d hang):
missing or non-C3D files, MIPS/SGI processor format and truncated parameter or
data sections are :class:`~gaitcli.errors.InputError`s of one line.
"""

from __future__ import annotations

import struct
import warnings
from pathlib import Path

from gaitcli.errors import GaitWarning, InputError

__all__ = ["check_file", "one_line", "warn", "param", "strings"]

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
    with open(path, "rb") as f:
        head = f.read(512)
        if size < 512:
            raise InputError(path, "header", f"not a C3D file: {size} bytes, shorter than the 512-byte header")
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
    n_points, n_analog, first, last = struct.unpack("<4H", head[2:10])
    data_block = struct.unpack("<H", head[16:18])[0]
    if data_block <= param_block:
        raise InputError(path, "header", f"not a C3D file: data block {data_block} is not after the parameters")
    if processor == 1:
        is_float = struct.unpack("<f", head[12:16])[0] < 0
    else:  # DEC F-float: the sign bit is the top bit of the first 16-bit word
        is_float = bool(head[13] & 0x80)
    if last < first:
        return None
    n_frames = last - first + 1
    need = (data_block - 1) * 512 + n_frames * (4 * n_points + n_analog) * (4 if is_float else 2)
    if size < need:
        raise InputError(
            path, "data",
            f"cannot read C3D: file is truncated ({size} bytes, the header's {n_frames} frames need {need})",
        )
    return n_frames


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
    return [str(s) for s in out]
