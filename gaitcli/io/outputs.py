"""Writers for a stage's outputs: CSV tables and ``summary.json`` (HDF5: :mod:`gaitcli.io.h5`).

A stage's whole output folder is staged in a temporary sibling folder and
renamed into place only when every file has been written (:func:`stage_folder`),
so an interrupted or failed run never leaves outputs that look valid.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.io.atomic import atomic_folder, atomic_path


def stage_folder(target: str | Path):
    """Yield a temporary folder; on success it replaces ``target`` (the previous run's outputs) whole
    (:func:`gaitcli.io.atomic.atomic_folder`)."""
    return atomic_folder(target)


def write_table(path: str | Path, columns: dict[str, np.ndarray], *, float_format: str = "%.6g") -> Path:
    """Write a CSV table (first column ``time_s`` or ``cycle_pct`` by the caller's order)."""
    frame = pd.DataFrame({name: np.asarray(values) for name, values in columns.items()})
    with atomic_path(path) as tmp:
        frame.to_csv(tmp, index=False, float_format=float_format, na_rep="NaN")
    return Path(path)


#: a cell's first characters that make a spreadsheet read it as a formula (OWASP's list for CSV injection)
FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def spreadsheet_text(text: str) -> str:
    """``text`` as a CSV cell a spreadsheet shows as text, not a formula: a ``'`` before a formula's first
    character, as spreadsheets themselves do (and before a leading ``'``, so :func:`plain_text` undoes it exactly)."""
    return "'" + text if text.startswith((*FORMULA_START, "'")) else text


def plain_text(cell: str) -> str:
    """The text :func:`spreadsheet_text` made ``cell`` of."""
    return cell[1:] if cell.startswith("'") else cell


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.bool_):
        return bool(value)
    if isinstance(value, Path):
        return str(value)
    return value


def write_json(path: str | Path, data: dict) -> Path:
    """Write ``summary.json`` (NaN/inf become null so any JSON reader accepts it)."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(_jsonable(data), indent=2) + "\n")
    return Path(path)
