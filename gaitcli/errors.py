"""Exception and warning classes with the CLI exit code each maps to."""

from __future__ import annotations

import math
from pathlib import Path

#: the longest piece of an input that an error message repeats
SHOWN_CHARACTERS = 80


def shown(value) -> str:
    """``repr(value)`` for an error message, cut to ``SHOWN_CHARACTERS`` (an input is never echoed whole)."""
    if type(value).__module__ == "numpy" and hasattr(value, "item") and getattr(value, "ndim", 1) == 0:
        value = value.item()  # 'abc', not np.str_('abc')
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10 ** SHOWN_CHARACTERS:
        digits = len(str(abs(value))) if value.bit_length() < 14_000 else math.floor(math.log10(abs(value))) + 1
        return f"a {digits}-digit integer"  # str() refuses more than 4300 digits
    text = repr(value)
    return text if len(text) <= SHOWN_CHARACTERS else text[:SHOWN_CHARACTERS - 1] + "…"


#: the longest path an error message repeats whole (PATH_MAX is 4096)
SHOWN_PATH = 200


def _shown_path(path: Path) -> str:
    """``path`` for a message: its start and its end around "…" when longer than ``SHOWN_PATH``."""
    text = str(path)
    return text if len(text) <= SHOWN_PATH else text[:SHOWN_PATH // 2 - 1] + "…" + text[-SHOWN_PATH // 2:]


#: the longest message an InputError prints (its middle cut; the "(expected …)" at its end kept)
SHOWN_MESSAGE = 600
_CONTROL = {c: f"\\x{c:02x}" for c in [*range(32), 127]} | {10: "\\n", 13: "\\r", 9: "\\t"}


def one_line(text: str) -> str:
    """``text`` with control characters (a newline in a folder name, an escape) written as escapes, and cut in
    the middle to :data:`SHOWN_MESSAGE` characters: a message is always one readable line."""
    text = text.translate(_CONTROL)
    if len(text) <= SHOWN_MESSAGE:
        return text
    tail = SHOWN_MESSAGE // 3
    return text[:SHOWN_MESSAGE - tail - 1] + "…" + text[-tail:]


class GaitError(Exception):
    """Base class of gaitcli's own errors; ``exit_code`` is what the CLI returns."""

    exit_code = 1


class InputError(GaitError):
    """Bad usage or bad input (exit code 2).

    The message is one line naming the file, the field and what was expected,
    e.g. ``subject.yaml: mass_kg: got -3 (expected a number > 0)``.
    """

    exit_code = 2

    def __init__(self, path: str | Path | None, field: str | None, problem: str):
        self.path = None if path is None else Path(path)
        if field and len(field) > SHOWN_CHARACTERS:  # e.g. a column name read from the file
            field = field[:SHOWN_CHARACTERS - 1] + "…"
        self.field = field
        self.problem = problem
        parts = [_shown_path(p) if p is self.path else p for p in (self.path, field) if p]
        super().__init__(one_line(": ".join(parts + [problem])))


class NotConvergedError(GaitError):
    """An optimization ended unconverged or infeasible (exit code 3); results were written."""

    exit_code = 3


class GaitWarning(UserWarning):
    """Something a lab should know about (missing plates, long gaps); the stage still writes."""
