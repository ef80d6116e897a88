"""Regression check of two output trees: every ``summary.json`` value and every CSV column, within tolerances.

``gait compare A B`` (README.md, "Comparing two output trees") calls :func:`compare_trees`, which reads both
trees and returns a :class:`Comparison`: the files it looked at and a tuple of :class:`Finding` (one per file,
column or summary key that differs beyond its tolerance). It writes nothing and decides no exit code; the CLI
prints the findings and exits 1 when there are any.

What is compared. Every ``*.csv`` and every ``summary.json`` under A is compared with the file of the same
relative path under B, so a tree may be one trial's output root (``gait_out/`` with its stage folders), a trial
folder, or a lab folder of many trials each with its ``gait_out/``. The relative path gives the trial (the folders
above ``gait_out``) and the stage (the folders below it, e.g. ``muscles/so``). A file or folder on one side only is
a finding. HDF5 files (binary; their numbers are in the CSVs), figures and hidden files (``io.atomic``'s
``.…part`` leftovers) are not compared, nor the summary keys and CSV columns of :data:`VOLATILE_KEYS` (run
times, versions, dates, hashes), which differ between two runs of the same inputs.

Values. Numbers are compared within the tolerance of their unit family (below); NaN (``null`` in
``summary.json``) equals NaN, and NaN on one side only is a difference; an infinity equals only the same
infinity. Text (events, sides, notes, booleans) must be equal. A table whose row count differs, a column or key
on one side only, a list of another length or a value of another type is a finding.

Unit families. A column's or key's family comes from its name, whose suffix carries the unit (:data:`UNIT_RULES`,
first match wins; a reference table's ``_mean``/``_sd`` suffix is dropped first, and a summary key without a unit
takes its parent's, e.g. ``segment_rms_marker_error_mm.pelvis`` is in mm). The default tolerances
(:data:`FAMILIES`; absolute, in the family's unit, converted to the column's: 1 mm is 0.001 for a ``_m`` column):

==============  =======  =========  ==================================================================
family          unit     tolerance  why
==============  =======  =========  ==================================================================
angle           deg      0.1        a tenth of the ~1° that skin artefact and marker placement leave
length          mm       1          the marker noise of a good lab (~1 mm); CSVs print 6 digits (µm)
speed           m/s      0.001      1 mm/s of a 1–2 m/s walk
time            s        0.001      1 ms: a tenth of a frame at 100 Hz
frequency       Hz       0.01       sampling rates and cut-offs are set, not measured
force           N        1          the force-plate noise (~1 N per channel)
force_per_kg    N/kg     0.01       1 N for a 75 kg subject
moment          N·m      0.5        0.01 N·m/kg for a 50 kg subject (stricter than per kg above 50 kg)
moment_per_kg   N·m/kg   0.01       under 1 % of the ~1.5 N·m/kg peak sagittal moments
power           W        1          1 W of muscle metabolic rates of up to a few hundred W
power_per_kg    W/kg     0.01       under 1 % of the ~1–3 W/kg peak joint powers
cost            J        1          1 J of a stride's ~200–300 J metabolic cost
cost_per_m      J/m      1          1 J/m of a cost of transport of ~200–350 J/m
mass            kg       0.01       10 g of a body or an added mass
percent         %        0.1        0.1 % of the gait cycle (a tenth of a sample at 101 samples)
fraction        —        0.001      activations and excitations (0–1): 0.1 % of full activation
unitless        —        1e-5 rel   relative: one unit in the 6th significant digit the CSVs print
==============  =======  =========  ==================================================================

(``unitless`` is relative, |A − B| ≤ 1e-5·max(|A|, |B|), with an absolute floor of 1e-9 near zero; counts such as
``frames`` and ``iterations`` are unitless, so they must be equal.)

Overrides: a YAML file (``--tolerances FILE``, :func:`read_tolerances`)::

    families:                # a family's tolerance, in the family's unit (table above)
      angle: 0.5
      moment_per_kg: 0.02
    columns:                 # a column's or summary key's tolerance, in its own unit; globs, first match wins
      "knee_*_moment": 2.0   # N·m
      "iterations": 3
    ignore:                  # columns and summary keys not compared at all (globs), besides VOLATILE_KEYS
      - "notes"

Column patterns match the column name (CSV) or the dotted summary key (``events[3].time_s``,
``joint_centre_gap_mm.hip_r``). An unknown family, an unknown top-level key or a negative tolerance is an
:class:`~gaitcli.errors.InputError` naming the file and the key.
"""

from __future__ import annotations

import fnmatch
import json
import math
import os
import re
from collections.abc import Iterable, Mapping
from contextlib import closing
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd

from gaitcli.core.validate import known_keys, number, text, unknown_key
from gaitcli.errors import InputError, shown
from gaitcli.io.yamlfile import read_yaml


@dataclass(frozen=True)
class Family:
    """A unit family: the unit its tolerance is given in, the default tolerance and why."""

    name: str
    unit: str
    tolerance: float
    why: str
    relative: bool = False  # |A − B| ≤ tolerance · max(|A|, |B|) instead of ≤ tolerance


#: the default tolerance of every unit family (module docstring's table)
FAMILIES: dict[str, Family] = {f.name: f for f in (
    Family("angle", "deg", 0.1, "a tenth of the ~1° that skin artefact and marker placement leave"),
    Family("length", "mm", 1.0, "the marker noise of a good lab (~1 mm)"),
    Family("speed", "m/s", 0.001, "1 mm/s of a 1–2 m/s walk"),
    Family("time", "s", 0.001, "1 ms: a tenth of a frame at 100 Hz"),
    Family("frequency", "Hz", 0.01, "sampling rates and cut-offs are set, not measured"),
    Family("force", "N", 1.0, "the force-plate noise (~1 N per channel)"),
    Family("force_per_kg", "N/kg", 0.01, "1 N for a 75 kg subject"),
    Family("moment", "N·m", 0.5, "0.01 N·m/kg for a 50 kg subject"),
    Family("moment_per_kg", "N·m/kg", 0.01, "under 1 % of the ~1.5 N·m/kg peak sagittal moments"),
    Family("power", "W", 1.0, "1 W of metabolic rates of up to a few hundred W"),
    Family("power_per_kg", "W/kg", 0.01, "under 1 % of the ~1–3 W/kg peak joint powers"),
    Family("cost", "J", 1.0, "1 J of a stride's ~200–300 J metabolic cost"),
    Family("cost_per_m", "J/m", 1.0, "1 J/m of a cost of transport of ~200–350 J/m"),
    Family("mass", "kg", 0.01, "10 g of a body or an added mass"),
    Family("percent", "%", 0.1, "0.1 % of the gait cycle"),
    Family("fraction", "", 0.001, "activations and excitations (0–1): 0.1 % of full activation"),
    Family("unitless", "", 1e-5, "one unit in the 6th significant digit the CSVs print", relative=True),
)}

#: a relative tolerance's absolute floor: values this close to zero are equal whatever their ratio
RELATIVE_FLOOR = 1e-9

#: (name pattern, family, the name's unit, factor from that unit to the family's); first match wins
UNIT_RULES: tuple[tuple[str, str, str, float], ...] = (
    (r"(_Nm_per_kg|_moment_per_kg|_Nm_kg)$", "moment_per_kg", "N·m/kg", 1.0),
    (r"_N_per_kg$", "force_per_kg", "N/kg", 1.0),
    (r"_J_per_m$", "cost_per_m", "J/m", 1.0),
    (r"(_Nm|_moment)$", "moment", "N·m", 1.0),
    (r"_N$", "force", "N", 1.0),
    (r"_J$", "cost", "J", 1.0),
    (r"_W_per_kg$", "power_per_kg", "W/kg", 1.0),
    (r"_W$", "power", "W", 1.0),
    (r"_m_s$", "speed", "m/s", 1.0),
    (r"_deg$", "angle", "deg", 1.0),
    (r"_rad$", "angle", "rad", 180.0 / math.pi),
    (r"_mm$", "length", "mm", 1.0),
    (r"_m$", "length", "m", 1000.0),
    (r"_kg$", "mass", "kg", 1.0),
    (r"_ms$", "time", "ms", 0.001),
    (r"_s$", "time", "s", 1.0),
    (r"_hz$", "frequency", "Hz", 1.0),
    (r"_pct$", "percent", "%", 1.0),
    # kinematics.csv, coordinates.csv and gait_cycle.csv name angles without a unit (README.md's outputs table):
    # m and deg
    (r"^pelvis_[xyz]$", "length", "m", 1000.0),
    (r"(^pelvis_rot_[xyz]|_flexion|_adduction|_rotation|_dorsiflexion|_tilt|_obliquity|_inversion|_progression)$",
     "angle", "deg", 1.0),
    (r"(_activation|_excitation)$", "fraction", "", 1.0),
)
_RULES = tuple((re.compile(p), fam, unit, factor) for p, fam, unit, factor in UNIT_RULES)
#: suffixes of a reference table's columns (``gait reference``) dropped before the unit is read
_STATISTIC = re.compile(r"_(mean|sd)$")

#: summary keys and CSV columns that differ between two runs of the same inputs: never compared
VOLATILE_KEYS = ("elapsed_s", "solve_time_s", "wall_time_s", "reused", "case_key", "version", "gaitcli_version",
                 "created", "created_at", "date", "hostname", "cwd")

#: per table file name, columns that record how a run went rather than what it found: a batch's ``status`` (a
#: rerun skips a current trial: "skipped" against "ok") and ``reason`` (a failure's message names the lab's own
#: absolute paths); its ``exit_code`` and figures are compared
RUN_STATE_COLUMNS = {"batch_summary.csv": ("status", "reason")}

#: the columns that say where in a table a difference is (those present, in this order)
WHERE_COLUMNS = ("time_s", "cycle_pct", "side", "stride", "case")

#: what a finding says is wrong (``Finding.problem``)
PROBLEMS = {
    "only_in_a": "only in A", "only_in_b": "only in B", "rows": "row counts differ",
    "column_only_in_a": "column only in A", "column_only_in_b": "column only in B",
    "key_only_in_a": "key only in A", "key_only_in_b": "key only in B", "length": "list lengths differ",
    "type": "types differ", "value": "beyond tolerance", "nan": "NaN on one side", "text": "text differs",
}


@dataclass(frozen=True)
class Rule:
    """How one column or summary key is compared: its family and unit, and the tolerance in that unit."""

    family: str
    unit: str
    tolerance: float
    relative: bool = False

    def describe(self) -> str:
        if self.relative:
            return f"{self.tolerance:g} rel"
        return f"{self.tolerance:g} {self.unit}".rstrip()


def unit_of(name: str) -> tuple[str, str, float] | None:
    """(family, unit, factor to the family's unit) from a column or key name, or None when it names no unit."""
    name = _STATISTIC.sub("", name)
    for pattern, family, unit, factor in _RULES:
        if pattern.search(name):
            return family, unit, factor
    return None


@dataclass(frozen=True)
class Tolerances:
    """The tolerances in force: per family (in the family's unit), per column pattern (in the column's unit,
    first match wins) and the patterns of columns and keys not compared."""

    families: Mapping[str, float] = field(default_factory=lambda: {n: f.tolerance for n, f in FAMILIES.items()})
    columns: tuple[tuple[str, float], ...] = ()
    ignore: tuple[str, ...] = ()

    def ignored(self, name: str, key: str | None = None) -> bool:
        """Whether the column or summary key ``name`` (``key``: its last part) is left out of the comparison."""
        key = name if key is None else key
        return key in VOLATILE_KEYS or any(fnmatch.fnmatchcase(n, p) for p in self.ignore for n in {name, key})

    def rule(self, name: str, unit_names: Iterable[str] = ()) -> Rule:
        """The rule for the column or dotted summary key ``name``. Its unit comes from the first of ``unit_names``
        (default: ``name`` itself; for a summary key, its keys from the nearest up) that names one; a column
        pattern matching ``name`` or its nearest key sets the tolerance in that unit."""
        unit_names = tuple(unit_names) or (name,)
        found = next((u for u in map(unit_of, unit_names) if u), None)
        family, unit, factor = found or ("unitless", "", 1.0)
        for pattern, tolerance in self.columns:
            if fnmatch.fnmatchcase(name, pattern) or fnmatch.fnmatchcase(unit_names[0], pattern):
                return Rule(family, unit, tolerance)
        return Rule(family, unit, self.families[family] / factor, FAMILIES[family].relative)


DEFAULT_TOLERANCES = Tolerances()

_TOLERANCE_KEYS = ("families", "columns", "ignore")


def read_tolerances(path: str | Path) -> Tolerances:
    """The tolerances of a YAML file (module docstring), defaults for what it does not say; a problem is an
    :class:`InputError` naming the file and the key."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "file not found (expected a tolerances YAML file)")
    data = read_yaml(path)
    if data is None:
        return DEFAULT_TOLERANCES
    if not isinstance(data, dict):
        raise InputError(path, None, f"a {type(data).__name__} (expected a mapping with keys "
                                     f"{', '.join(_TOLERANCE_KEYS)})")
    known_keys(data, _TOLERANCE_KEYS, path=path)
    families = dict(DEFAULT_TOLERANCES.families)
    for key, value in _mapping(data.get("families"), "families", path).items():
        if key not in FAMILIES:
            raise unknown_key(key, FAMILIES, where="families.", path=path)
        families[key] = number(value, where=f"families.{key}", path=path, low=0.0)
    columns = tuple((text(key, where="columns", path=path, expected="a column name or pattern"),
                     number(value, where=f"columns.{key}", path=path, low=0.0))
                    for key, value in _mapping(data.get("columns"), "columns", path).items())
    ignore = data.get("ignore") or []
    if not isinstance(ignore, list):
        raise InputError(path, "ignore", f"a {type(ignore).__name__} (expected a list of column or key patterns)")
    ignore = tuple(text(p, where=f"ignore[{k}]", path=path, expected="a column or key pattern")
                   for k, p in enumerate(ignore))
    return Tolerances(families=families, columns=columns, ignore=ignore)


def _mapping(value, key: str, path: Path) -> dict:
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise InputError(path, key, f"a {type(value).__name__} (expected a mapping of names to tolerances)")
    return value


def split_path(relative: str) -> tuple[str, str, str]:
    """(trial, stage, file) of a path relative to a tree's root: the folders above ``gait_out``, those below it,
    and the file name (a folder's path ends in ``/`` and has no file). Without ``gait_out`` the stage is the
    folder."""
    parts = relative.split("/")
    name, folders = parts[-1], parts[:-1]
    if "gait_out" in folders:
        k = len(folders) - 1 - folders[::-1].index("gait_out")
        return "/".join(folders[:k]), "/".join(folders[k + 1:]), name
    return "", "/".join(folders), name


@dataclass(frozen=True)
class Finding:
    """One thing that differs: a file or folder on one side only, or a column or summary key of a file in both.

    ``path``: relative to the roots (POSIX; a folder ends in ``/``); ``column``: the CSV column or dotted summary
    key ("" for the file); ``problem``: a key of :data:`PROBLEMS`; ``difference``: the largest |A − B| beyond
    tolerance (``value``, in ``unit``), NaN otherwise; ``family``, ``tolerance`` (in ``unit``) and ``relative``:
    the rule it broke (``value``, ``nan``); ``where``: the row of that difference (``time_s=… (line …)``);
    ``detail``: the values or counts, for people.
    """

    path: str
    column: str = ""
    problem: str = "value"
    difference: float = math.nan
    family: str = ""
    tolerance: float = math.nan
    relative: bool = False
    unit: str = ""
    where: str = ""
    detail: str = ""

    @property
    def trial(self) -> str:
        return split_path(self.path)[0]

    @property
    def stage(self) -> str:
        return split_path(self.path)[1]

    @property
    def file(self) -> str:
        return split_path(self.path)[2]

    @property
    def tolerance_text(self) -> str:
        """``0.5 N·m``, ``1e-05 rel``, or "" where no tolerance applies."""
        if math.isnan(self.tolerance):
            return ""
        return Rule(self.family, self.unit, self.tolerance, self.relative).describe()

    def to_json(self) -> dict:
        data = {"trial": self.trial, "stage": self.stage, "file": self.file, **asdict(self)}
        for key in ("difference", "tolerance"):
            data[key] = None if not math.isfinite(data[key]) else data[key]
        return data


@dataclass(frozen=True)
class Comparison:
    """What :func:`compare_trees` found: every relative path seen (in A or B), those that differ, the findings."""

    a: Path
    b: Path
    files: tuple[str, ...]
    differing: tuple[str, ...]
    findings: tuple[Finding, ...]

    @property
    def ok(self) -> bool:
        return not self.findings

    def summary_line(self) -> str:
        return f"{len(self.files)} files compared, {len(self.differing)} differ"

    def to_json(self) -> dict:
        return {"a": str(self.a), "b": str(self.b), "files_compared": len(self.files),
                "files_differing": len(self.differing), "differing": list(self.differing),
                "findings": [f.to_json() for f in self.findings]}


def tree_files(root: str | Path) -> list[str]:
    """The relative paths (POSIX, sorted) of every CSV and ``summary.json`` under ``root``, hidden ones left out."""
    root = Path(root)
    out = []

    def unreadable(exc: OSError):  # a folder that cannot be listed is no folder without files
        raise InputError(exc.filename, None, f"cannot be read ({exc.strerror}; expected a readable output "
                                             "folder)") from None

    for top, folders, files in os.walk(root, onerror=unreadable):
        here = Path(top).relative_to(root)
        folders[:] = [f for f in folders if not (f.startswith(".") or f == "__pycache__")]
        for name in files:
            if name.startswith("."):
                continue
            if (Path(name).suffix.lower() == ".csv" or name == "summary.json") and Path(top, name).is_file():
                out.append((here / name).as_posix())
    return sorted(out)


def _check_root(root: Path, which: str) -> Path:
    if not root.exists():
        raise InputError(root, None, f"not found (expected the output folder {which})")
    if not root.is_dir():
        raise InputError(root, None, f"not a folder (expected the output folder {which})")
    return root


def outputs_only(rel: str) -> bool:
    """A relative path inside a ``gait_out`` folder (a stage's output, not a trial's input or truth)."""
    return "gait_out" in rel.split("/")[:-1]


def compare_trees(a: str | Path, b: str | Path, *, tolerances: Tolerances = DEFAULT_TOLERANCES,
                  select=None) -> Comparison:
    """Compare every CSV and ``summary.json`` under ``a`` with the same relative path under ``b`` (module
    docstring); ``select(relative path) -> bool`` keeps only some (e.g. :func:`outputs_only`). Reads only;
    unreadable files and bad roots are :class:`InputError`."""
    a, b = _check_root(Path(a), "A"), _check_root(Path(b), "B")
    in_a, in_b = tree_files(a), tree_files(b)
    if select is not None:
        in_a, in_b = [r for r in in_a if select(r)], [r for r in in_b if select(r)]
    if not in_a and not in_b:
        raise InputError(a, None, f"no CSV or summary.json files under it or under {b} (expected gait output trees)")
    both = sorted(set(in_a) & set(in_b))
    findings: list[Finding] = []
    differing: set[str] = set()
    for only, side, other in ((sorted(set(in_a) - set(in_b)), "a", b), (sorted(set(in_b) - set(in_a)), "b", a)):
        differing.update(only)
        findings += _missing(only, side, other)
    for rel in both:
        found = (_compare_json if rel.endswith(".json") else _compare_csv)(a / rel, b / rel, rel, tolerances)
        if found:
            differing.add(rel)
            findings += found
    findings.sort(key=lambda f: (f.path.rstrip("/"), f.problem not in ("only_in_a", "only_in_b")))
    return Comparison(a, b, tuple(sorted(set(in_a) | set(in_b))), tuple(sorted(differing)), tuple(findings))


def _missing(paths: list[str], side: str, other: Path) -> list[Finding]:
    """Findings for files on one side only: one per file, or one per topmost folder missing on the other side."""
    groups: dict[str, list[str]] = {}
    for rel in paths:
        parts = rel.split("/")
        folders = ("/".join(parts[:k]) for k in range(1, len(parts)))
        top = next((f"{folder}/" for folder in folders if not (other / folder).is_dir()), rel)
        groups.setdefault(top, []).append(rel)
    where = "A" if side == "a" else "B"
    return [Finding(top, problem=f"only_in_{side}",
                    detail=(f"folder of {len(files)} file(s) only in {where}" if top.endswith("/") else
                            f"only in {where}"))
            for top, files in groups.items()]


# -- CSV tables -------------------------------------------------------------------------------------------------

#: cells of one table read at a time (per side): memory stays flat in the tables' length
CHUNK_CELLS = 500_000


def _csv_chunks(path: Path) -> Iterable[pd.DataFrame]:
    """The table in chunks of about :data:`CHUNK_CELLS` cells, as text (an empty file: one empty table); the
    row index runs on across chunks."""
    try:
        try:
            columns = pd.read_csv(path, dtype=str, keep_default_na=False, nrows=0).columns
        except pd.errors.EmptyDataError:
            yield pd.DataFrame()
            return
        rows = max(1, CHUNK_CELLS // max(1, len(columns)))
        empty = True
        with pd.read_csv(path, dtype=str, keep_default_na=False, chunksize=rows) as reader:
            for chunk in reader:
                empty = False
                yield chunk
        if empty:
            yield pd.DataFrame(columns=columns)
    except (pd.errors.ParserError, UnicodeDecodeError, ValueError) as exc:
        raise InputError(path, None, f"not a readable CSV table ({str(exc).splitlines()[0][:80]})") from None
    except OSError as exc:  # unreadable (permission denied), a folder by that name
        raise InputError(path, None, f"cannot be read ({exc.strerror})") from None


def _numeric(cells: pd.Series, path: Path) -> np.ndarray | None:
    """The column as floats (empty cells NaN), or None when a cell is not a number (a text column). A number
    beyond the range of a double (``1e400``) is an error: read as infinity it would equal every other."""
    text = cells.to_numpy(dtype=str)
    try:
        values = np.where(text == "", "nan", text).astype(float)
    except ValueError:
        return None
    beyond = np.flatnonzero(np.isinf(values) & ~np.isin(np.char.lower(np.char.strip(text)), _INFINITIES))
    if beyond.size:
        k = beyond[0]
        raise InputError(path, str(cells.name), f"{text[k][:40]} on line {cells.index[k] + 2} is beyond the range "
                                                f"of a double (expected a finite number, inf or -inf)")
    return values


#: how an infinity is spelled in a table (numpy and pandas write ``inf``)
_INFINITIES = ("inf", "+inf", "-inf", "infinity", "+infinity", "-infinity")


def _where(table: pd.DataFrame, row: int) -> str:
    labels = [f"{c}={table[c].iloc[row]}" for c in WHERE_COLUMNS if c in table.columns]
    return f"{' '.join(labels)} (line {table.index[row] + 2})".strip()


def _compare_csv(path_a: Path, path_b: Path, rel: str, tol: Tolerances) -> list[Finding]:
    """Two tables compared chunk by chunk (:func:`_csv_chunks`); each column's findings over the chunks merged
    (:func:`_merged`). A column is compared as text in the chunks where a cell of it is not a number;
    :data:`RUN_STATE_COLUMNS` are not compared."""
    tol = replace(tol, ignore=tol.ignore + RUN_STATE_COLUMNS.get(Path(rel).name, ()))
    with closing(_csv_chunks(path_a)) as chunks_a, closing(_csv_chunks(path_b)) as chunks_b:
        return _compare_chunks(chunks_a, chunks_b, rel, tol, path_a, path_b)


def _compare_chunks(chunks_a, chunks_b, rel: str, tol: Tolerances, path_a: Path, path_b: Path) -> list[Finding]:
    ta, tb = next(chunks_a), next(chunks_b)
    out = [Finding(rel, c, f"column_only_in_{side}", detail=f"only in {side.upper()}")
           for side, cols, others in (("a", ta.columns, tb.columns), ("b", tb.columns, ta.columns))
           for c in cols if c not in others and not tol.ignored(c)]
    columns = [c for c in ta.columns if c in tb.columns and not tol.ignored(c)]
    found: dict[str, list[Finding]] = {}
    rows_a = rows_b = 0
    while ta is not None or tb is not None:
        rows_a += 0 if ta is None else len(ta)
        rows_b += 0 if tb is None else len(tb)
        if ta is not None and tb is not None and rows_a == rows_b:  # the same rows on both sides
            for column in columns:
                xa, xb = _numeric(ta[column], path_a), _numeric(tb[column], path_b)
                if xa is None or xb is None:
                    new = _text_finding(rel, column, ta[column].to_numpy(), tb[column].to_numpy(), ta)
                else:
                    new = _number_findings(rel, column, xa, xb, tol.rule(column), ta)
                found.setdefault(column, []).extend(new)
        else:
            found = {}  # the row counts differ: that is the finding, counted to the end
        ta, tb = next(chunks_a, None), next(chunks_b, None)
    if rows_a != rows_b:
        return [Finding(rel, "", "rows", difference=float(abs(rows_a - rows_b)), detail=f"{rows_a} rows in A, "
                        f"{rows_b} in B")] + out
    return out + [merged for column in columns for merged in _merged(found.get(column, []), rows_a)]


#: the count a table finding's detail ends with: "(N rows)" or "(N of M rows beyond tolerance)"
_COUNT = re.compile(r" \((\d+)( of \d+)?( rows[^)]*)\)$")


def _merged(findings: list[Finding], rows: int) -> list[Finding]:
    """One finding per problem from one column's findings over the chunks of a ``rows``-row table: the first NaN
    or text difference, the largest value difference, each with the rows counted over all chunks."""
    out = []
    for problem in dict.fromkeys(f.problem for f in findings):
        same = [f for f in findings if f.problem == problem]
        chosen = max(same, key=lambda f: f.difference) if problem == "value" else same[0]
        match = _COUNT.search(chosen.detail)
        if match and len(same) > 1:
            total = sum(int(m.group(1)) for f in same if (m := _COUNT.search(f.detail)))
            of = f" of {rows}" if match.group(2) else ""
            chosen = replace(chosen, detail=chosen.detail[:match.start()] + f" ({total}{of}{match.group(3)})")
        out.append(chosen)
    return out


def _text_finding(rel: str, column: str, a: np.ndarray, b: np.ndarray, table: pd.DataFrame | None) -> list[Finding]:
    rows = np.flatnonzero(a != b)
    if not rows.size:
        return []
    k = int(rows[0])
    detail = f"{shown(a[k])} in A, {shown(b[k])} in B" + (f" ({rows.size} rows)" if table is not None else "")
    return [Finding(rel, column, "text", where=_where(table, k) if table is not None else "", detail=detail)]


def _rule_fields(rule: Rule) -> dict:
    return {"family": rule.family, "tolerance": rule.tolerance, "relative": rule.relative, "unit": rule.unit}


def _number_findings(rel: str, column: str, a: np.ndarray, b: np.ndarray, rule: Rule,
                     table: pd.DataFrame | None) -> list[Finding]:
    """A ``nan`` finding for NaN on one side only, a ``value`` one for differences beyond ``rule``'s tolerance."""
    out = []
    nan_a, nan_b = np.isnan(a), np.isnan(b)
    lonely = np.flatnonzero(nan_a != nan_b)
    if lonely.size:
        k = int(lonely[0])
        detail = f"{'NaN' if nan_a[k] else f'{a[k]:g}'} in A, {'NaN' if nan_b[k] else f'{b[k]:g}'} in B"
        out.append(Finding(rel, column, "nan", difference=math.inf, **_rule_fields(rule),
                           where=_where(table, k) if table is not None else "",
                           detail=detail + (f" ({lonely.size} rows)" if table is not None else "")))
    with np.errstate(invalid="ignore"):  # inf − inf: a difference of its own
        both = ~(nan_a | nan_b) & (a != b)
        diff = np.where(both, np.abs(a - b), 0.0)
        diff[both & np.isnan(diff)] = math.inf
        if rule.relative:
            allowed = np.maximum(rule.tolerance * np.maximum(np.abs(a), np.abs(b)), RELATIVE_FLOOR)
        else:
            allowed = np.full(a.shape, rule.tolerance)
    # an infinity differs from any other value: a tolerance relative to it would be infinite too
    beyond = both & ((diff > allowed * (1 + 1e-9)) | ~(np.isfinite(a) & np.isfinite(b)))
    if beyond.any():
        k = int(np.flatnonzero(beyond)[np.argmax(diff[beyond])])
        count = f" ({int(beyond.sum())} of {a.size} rows beyond tolerance)" if table is not None else ""
        out.append(Finding(rel, column, "value", difference=float(diff[k]), **_rule_fields(rule),
                           where=_where(table, k) if table is not None else "",
                           detail=f"{a[k]:.6g} in A, {b[k]:.6g} in B{count}"))
    return out


# -- summary.json ---------------------------------------------------------------------------------------------

#: the deepest nesting and the longest integer a summary.json may hold (gaitcli's own are 3 deep, 20 digits)
MAX_JSON_DEPTH = 50
MAX_JSON_DIGITS = 300


def _read_json(path: Path):
    def parse_int(digits: str) -> int:
        if len(digits.lstrip("-")) > MAX_JSON_DIGITS:
            raise InputError(path, None, f"a {len(digits.lstrip('-'))}-digit integer (expected at most "
                                         f"{MAX_JSON_DIGITS} digits)")
        return int(digits)

    def parse_float(digits: str) -> float:
        value = float(digits)
        if math.isinf(value):  # JSON writes an infinity as Infinity, which parse_constant reads
            raise InputError(path, None, f"{digits[:40]} is beyond the range of a double (expected a finite "
                                         f"number or Infinity)")
        return value

    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(path, None, f"not valid JSON ({exc.__class__.__name__})") from None
    except OSError as exc:
        raise InputError(path, None, f"cannot be read ({exc.strerror})") from None
    if _depth(text) > MAX_JSON_DEPTH:  # before parsing: json and _walk recurse once per level
        raise InputError(path, None, f"nested more than {MAX_JSON_DEPTH} levels deep (expected a summary)")
    try:
        return json.loads(text, parse_int=parse_int, parse_float=parse_float)
    except json.JSONDecodeError as exc:
        raise InputError(path, None, f"not valid JSON ({exc.__class__.__name__})") from None


def _depth(text: str) -> int:
    """The deepest nesting of brackets and braces outside strings in JSON ``text``."""
    depth = deepest = 0
    for match in re.finditer(r'"(?:[^"\\]|\\.)*"|[\[{]|[\]}]', text):
        token = match.group()
        if token in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif token in "]}":
            depth -= 1
    return deepest


def _compare_json(path_a: Path, path_b: Path, rel: str, tol: Tolerances) -> list[Finding]:
    out: list[Finding] = []
    _walk(_read_json(path_a), _read_json(path_b), "", (), rel, tol, out)
    return out


def _kind(value) -> str:
    if value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)):
        return "number"
    return {bool: "boolean", str: "text", list: "list", dict: "mapping"}.get(type(value), type(value).__name__)


def _walk(a, b, name: str, keys: tuple[str, ...], rel: str, tol: Tolerances, out: list[Finding]) -> None:
    """Compare the summary values ``a`` and ``b`` at dotted key ``name`` (``keys``: the mapping keys on the way
    there, nearest last), appending findings to ``out``."""
    kind_a, kind_b = _kind(a), _kind(b)
    if kind_a != kind_b:
        out.append(Finding(rel, name, "type", detail=f"{kind_a} in A, {kind_b} in B"))
    elif kind_a == "mapping":
        for key in [*a, *(k for k in b if k not in a)]:
            child = f"{name}.{key}" if name else str(key)
            if tol.ignored(child, str(key)):
                continue
            if key not in b or key not in a:
                side = "a" if key in a else "b"
                out.append(Finding(rel, child, f"key_only_in_{side}", detail=f"only in {side.upper()}"))
            else:
                _walk(a[key], b[key], child, (*keys, str(key)), rel, tol, out)
    elif kind_a == "list":
        if len(a) != len(b):
            out.append(Finding(rel, name, "length", difference=float(abs(len(a) - len(b))),
                               detail=f"{len(a)} items in A, {len(b)} in B"))
        else:
            for k, (x, y) in enumerate(zip(a, b)):
                _walk(x, y, f"{name}[{k}]", keys, rel, tol, out)
    elif kind_a == "number":
        x, y = (np.array([math.nan if v is None else float(v)]) for v in (a, b))
        rule = tol.rule(name, tuple(reversed(keys)))
        out += _number_findings(rel, name, x, y, rule, None)
    else:
        out += _text_finding(rel, name, np.array([a], dtype=object), np.array([b], dtype=object), None)


def finding_rows(comparison: Comparison) -> list[tuple[str, ...]]:
    """The findings as the CLI's table rows, :data:`TABLE_HEADER` order, every cell text."""
    rows = []
    for f in comparison.findings:
        if f.problem == "value":
            diff = f"{f.difference:.4g} {f.unit}".rstrip()
        else:
            diff = f.detail if f.problem != "nan" else f"NaN: {f.detail}"
        if f.problem == "value" and f.detail:
            diff += f"  ({f.detail.split(' (')[0]})"
        rows.append((f.trial or ".", f.stage or ".", f.file or "(folder)", f.column or "—", diff,
                     f.tolerance_text or "—", f.where or "—"))
    return rows


#: the CLI table's columns
TABLE_HEADER = ("trial", "stage", "file", "column", "max |difference|", "tolerance", "where")
