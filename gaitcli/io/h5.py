"""HDF5 files of the stages: one writer and one reader for every stage result.

A stage result is a dataclass of arrays, numbers, text, nested dataclasses and
dicts or lists of them. :func:`record_datasets` turns it into datasets under a
group (one dataset per array field, one group per nested dataclass, dict or
list), with the unit read from the field name's suffix (``force_N`` → ``N``,
``cop_m`` → ``m``; :data:`UNIT_SUFFIXES`); :func:`read_record` rebuilds the same
dataclass from the group, guided by its type annotations. So a result is written
and read by the same two functions, and a later stage gets back exactly the
object an earlier stage returned. Text is stored as UTF-8 strings and read with
h5py's ``.asstr()``. Tables for people (a 2-D dataset with its column names in an
attribute) are read as a :class:`ColumnTable`. Files read back are input: every
reader opens them through :func:`open_h5`, so a damaged or foreign file is an
:class:`~gaitcli.errors.InputError`, and no dataset is read past :data:`H5_MAX_BYTES`.

Root attributes (:func:`provenance`): gaitcli version, resolved config as YAML,
the input files' SHA-256, creation time, and the trial's processing history.
"""

from __future__ import annotations

import dataclasses
import json
import types
import typing
from contextlib import contextmanager
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import h5py
import numpy as np

from gaitcli import __version__
from gaitcli.errors import SHOWN_CHARACTERS, InputError, shown
from gaitcli.io.atomic import atomic_path

#: field-name suffix → unit (longest match first); fields without one are dimensionless ("1")
UNIT_SUFFIXES = {
    "_J_per_m": "J/m", "_m_s2": "m/s^2", "_m_s": "m/s", "_Nms_per_rad": "N*m*s/rad", "_kgm2": "kg*m^2",
    "_Nm": "N*m", "_hz": "Hz", "_kg": "kg", "_deg": "deg", "_rad": "rad", "_N": "N", "_m": "m", "_s": "s",
    "_W": "W", "_J": "J",
}


def unit_of(name: str) -> str:
    """The unit a field name declares by its suffix (``"1"`` when it declares none)."""
    for suffix, unit in sorted(UNIT_SUFFIXES.items(), key=lambda kv: -len(kv[0])):
        if name.endswith(suffix):
            return unit
    return "1"


@dataclass
class Dataset:
    """One HDF5 dataset: values, their units, and optional extra attributes (e.g. sign convention)."""

    values: Any
    units: str
    attrs: dict = field(default_factory=dict)


def provenance(config_yaml: str, inputs: dict[str, str], history: tuple[str, ...] = ()) -> dict:
    """Root attributes every HDF5 file carries: version, resolved config, input SHA-256, time, history."""
    return {
        "gaitcli_version": __version__,
        "config_yaml": config_yaml,
        "input_sha256": json.dumps(inputs, indent=0),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "history": "\n".join(history),
    }


def write_h5(path: str | Path, datasets: dict[str, Dataset], root_attrs: dict) -> Path:
    """Write one HDF5 file atomically; dataset names may contain '/' for groups; every dataset gets ``units``."""
    with atomic_path(path) as tmp:
        with h5py.File(tmp, "w") as h5:
            for key, value in root_attrs.items():
                h5.attrs[key] = "none" if value is None else value
            for name, ds in datasets.items():
                values = np.asarray(ds.values)
                if values.dtype.kind in "UO":
                    values = values.astype(h5py.string_dtype())
                d = h5.create_dataset(name, data=values)
                d.attrs["units"] = ds.units
                for key, value in ds.attrs.items():
                    d.attrs[key] = "none" if value is None else value
    return Path(path)


#: the most bytes one HDF5 dataset may hold, decompressed, for gaitcli to read it: above any dataset it writes
#: (a trial at the C3D ceiling of 40 million numbers is at most 320 MB of float64); a few kB of compressed
#: chunks can otherwise claim gigabytes
H5_MAX_BYTES = 512 * 2**20


def checked(dataset: h5py.Dataset) -> h5py.Dataset:
    """``dataset`` when its decompressed size (shape × item size, from the metadata) is within
    :data:`H5_MAX_BYTES`; else an :class:`InputError` naming the file and the dataset, before any reading."""
    if not isinstance(dataset, h5py.Dataset):  # a damaged or foreign file: a group where a dataset belongs
        raise InputError(dataset.file.filename, dataset.name.lstrip("/"), "a group (expected a dataset)")
    if dataset.external or dataset.is_virtual:  # reading would open other files (a FIFO blocks for ever)
        raise InputError(dataset.file.filename, dataset.name.lstrip("/"),
                         f"{'external storage' if dataset.external else 'a virtual dataset'}: its data lie in other "
                         "files (expected a dataset stored in the file itself)")
    size = int(np.prod(dataset.shape, dtype=object)) * dataset.dtype.itemsize if dataset.shape else 0
    if size > H5_MAX_BYTES:
        raise InputError(dataset.file.filename, dataset.name.lstrip("/"),
                         f"dataset of shape {dataset.shape} and {dataset.dtype.itemsize}-byte items holds "
                         f"{size} bytes decompressed, more than gaitcli reads ({H5_MAX_BYTES})")
    return dataset


def strings(dataset: h5py.Dataset) -> np.ndarray:
    """A string dataset as an array of ``str``."""
    return np.asarray(checked(dataset).asstr()[()], dtype=str)


# ----------------------------------------------------------------------------------- records

def record_datasets(prefix: str, obj: Any, *, units: str | None = None) -> dict[str, Dataset]:
    """The datasets that store ``obj`` (a dataclass, dict, list, array or scalar) under ``prefix``."""
    if dataclasses.is_dataclass(obj):
        out = {f"{prefix}/.type": Dataset(type(obj).__name__, "1")}
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if value is not None:
                out.update(record_datasets(f"{prefix}/{f.name}", value, units=unit_of(f.name)))
        return out
    if isinstance(obj, dict):
        out = {f"{prefix}/.keys": Dataset(np.array([str(k) for k in obj], dtype=object), "1")}
        for i, (key, value) in enumerate(obj.items()):
            if value is not None:
                out.update(record_datasets(f"{prefix}/{_member(key, i)}", value, units=units))
        return out
    if isinstance(obj, list) or (isinstance(obj, tuple) and obj and dataclasses.is_dataclass(obj[0])):
        out = {f"{prefix}/.length": Dataset(len(obj), "1")}
        for i, value in enumerate(obj):
            out.update(record_datasets(f"{prefix}/{i}", value, units=units))
        return out
    if isinstance(obj, Path):
        obj = str(obj)
    values = np.asarray(obj)
    if values.dtype.kind in "UO" or isinstance(obj, str):
        values = np.asarray(obj, dtype=object)
    return {prefix: Dataset(values, units or "1")}


def _member(key, index: int) -> str:
    """The group member holding a dict entry: the key itself where it is a plain name, else its index."""
    key = str(key)
    return key if key and "/" not in key and not key.startswith(".") and not key.isdigit() else str(index)


def _read_untyped(node):
    if isinstance(node, h5py.Group):
        if ".keys" in node:
            keys = strings(node[".keys"])
            return {str(k): _read_untyped(node[_member(k, i)]) for i, k in enumerate(keys) if _member(k, i) in node}
        if ".length" in node:
            return [_read_untyped(node[str(i)]) for i in range(int(node[".length"][()]))]
        return {name: _read_untyped(node[name]) for name in node if not name.startswith(".")}
    if node.dtype.kind == "O":
        return str(node.asstr()[()]) if node.shape == () else strings(node)
    value = checked(node)[()]
    return value.item() if isinstance(value, np.generic) else value


def _strip_optional(hint):
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(hint) if a is not type(None)]
        return args[0] if len(args) == 1 else hint
    return hint


def _read_value(node, hint):
    hint = _strip_optional(hint)
    origin = typing.get_origin(hint)
    if dataclasses.is_dataclass(hint):
        return read_record(node, hint)
    if hint in (Any, dict, list) or (origin is dict and not typing.get_args(hint)):
        return _read_untyped(node)
    if hint is tuple:
        value = _read_untyped(node)
        return tuple(value.tolist() if isinstance(value, np.ndarray) else value)
    if origin is dict:
        _, value_hint = typing.get_args(hint)
        keys = strings(node[".keys"])
        return {str(k): _read_value(node[_member(k, i)], value_hint) if _member(k, i) in node else None
                for i, k in enumerate(keys)}
    if origin is list or (origin is tuple and isinstance(node, h5py.Group)):
        args = typing.get_args(hint)
        item_hint = args[0] if args else Any
        items = [_read_value(node[str(i)], item_hint) for i in range(int(node[".length"][()]))]
        return items if origin is list else tuple(items)
    checked(node)  # a value: a dataset within the size limit (a group in a damaged file: InputError)
    if origin is tuple:
        args = typing.get_args(hint)
        item = args[0] if args else float
        values = strings(node) if node.dtype.kind == "O" else checked(node)[()]
        return tuple(item(v) if item in (str, float, int, bool) else v for v in np.atleast_1d(values))
    if hint is str:
        return str(node.asstr()[()])
    if hint in (float, int, bool):
        return hint(node[()])
    if node.dtype.kind == "O":
        return strings(node)
    return checked(node)[()]


def _written_class(group: h5py.Group, cls):
    """The dataclass a record was written from: ``cls``, or the subclass of it (imported, at any depth) that
    its ``.type`` names, as a field typed by a base class holds one of its kinds (a prosthesis law)."""
    if ".type" not in group:
        return cls
    name = str(group[".type"].asstr()[()])
    kinds = list(cls.__subclasses__())
    while kinds and name != cls.__name__:
        kind = kinds.pop()
        if kind.__name__ == name and dataclasses.is_dataclass(kind):
            return kind
        kinds.extend(kind.__subclasses__())
    return cls


def read_record(group: h5py.Group, cls):
    """Rebuild the dataclass ``cls`` (or the subclass the record names) from the group :func:`record_datasets`
    wrote (missing fields: defaults)."""
    cls = _written_class(group, cls)
    hints = typing.get_type_hints(cls)
    values = {}
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        if f.name in group:
            values[f.name] = _read_value(group[f.name], hints[f.name])
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            values[f.name] = None  # an optional field written as absent
    return cls(**values)


def read_records(group: h5py.Group, cls) -> list:
    """The list of ``cls`` records :func:`record_datasets` wrote for a list under ``group``."""
    return _read_value(group, list[cls])


@contextmanager
def open_h5(path: str | Path, what: str = "gaitcli"):
    """``h5py.File(path, "r")`` for reading an output back: a damaged file, or one that lacks what the block
    reads (KeyError) or holds it in another shape or type, is an InputError naming it (``what``: whose file
    was expected, e.g. ``"gait idyn"``)."""
    try:
        h5 = h5py.File(path, "r")
    except FileNotFoundError:
        raise InputError(path, None, f"file not found (expected the HDF5 file of {what})") from None
    except OSError as exc:  # not HDF5, truncated, unreadable
        raise InputError(path, None, f"not a readable HDF5 file ({_first_line(exc)}; expected {what}'s)") from None
    try:
        with h5:
            _refuse_outside_links(h5, path)
            yield h5
    except (KeyError, ValueError, TypeError, IndexError, OSError, RuntimeError) as exc:  # RuntimeError: link loops
        raise InputError(path, None, f"not an HDF5 file of {what} ({type(exc).__name__}: {_first_line(exc)})") \
            from None


#: the most links an HDF5 file gaitcli reads may hold (its own files hold a few hundred)
H5_MAX_LINKS = 100_000


def _refuse_outside_links(h5: h5py.File, path) -> None:
    """An InputError for a link that leaves the file (an external link), before anything is read through it;
    also for more than :data:`H5_MAX_LINKS` links."""
    seen = 0

    def visit(name: str, link):  # a value other than None stops the visit (raising inside h5py's lock cannot)
        nonlocal seen
        seen += 1
        if isinstance(link, h5py.ExternalLink):
            return name, link.filename
        return (None, None) if seen > H5_MAX_LINKS else None

    stopped = h5.visititems_links(visit)
    if stopped is None:
        return
    name, filename = stopped
    if name is None:
        raise InputError(path, None, f"more than {H5_MAX_LINKS:,} links (expected gaitcli's own HDF5 file)")
    raise InputError(path, name, f"a link to {shown(filename)} outside the file (expected gaitcli's own HDF5 "
                                 "file, which holds its data itself)")


def _first_line(exc: BaseException) -> str:
    lines = str(exc).strip().splitlines() or [""]
    return lines[0][:SHOWN_CHARACTERS]


def read_result(path: str | Path, cls, prefix: str = "result", *, what: str = "gaitcli"):
    """The stage result of type ``cls`` stored under ``prefix`` in the HDF5 file ``path`` (``cls``: a dataclass,
    or a type hint such as ``list[Stride]``); a damaged or foreign file is an InputError (:func:`open_h5`,
    ``what``: whose file was expected)."""
    with open_h5(path, what) as h5:
        return _read_value(h5[prefix], cls)


def read_field(path: str | Path, cls, name: str, prefix: str = "result", *, what: str = "gaitcli"):
    """The field ``name`` alone of the ``cls`` record stored under ``prefix`` in ``path``, typed by ``cls``'s
    annotation (a missing field, or a damaged or foreign file, is an InputError)."""
    with open_h5(path, what) as h5:
        return _read_value(h5[f"{prefix}/{name}"], typing.get_type_hints(cls)[name])


def file_attrs(path: str | Path, *, what: str = "gaitcli") -> dict[str, Any]:
    """The root attributes of an HDF5 file gaitcli wrote (:func:`provenance` and a stage's own, e.g. ``trial``,
    ``stage_key``); a damaged or foreign file is an InputError."""
    with open_h5(path, what) as h5:
        return {key: h5.attrs[key] for key in h5.attrs}


# ----------------------------------------------------------------------------------- tables

@dataclass(frozen=True)
class ColumnTable:
    """A 2-D dataset whose columns are named by an attribute (``columns``; ``joints`` for per-joint arrays):
    ``values`` (rows, columns) in ``units``, with the sign ``convention`` its writer recorded."""

    values: np.ndarray
    columns: tuple[str, ...]
    units: str = "1"
    convention: str = ""

    def index(self, name: str) -> int:
        return self.columns.index(name)

    def column(self, name: str) -> np.ndarray:
        """The values (rows,) of the column ``name`` (ValueError when there is none)."""
        return self.values[:, self.columns.index(name)]


def column_table(dataset: h5py.Dataset, names: str = "columns") -> ColumnTable:
    """The :class:`ColumnTable` of a dataset whose attribute ``names`` lists its columns, comma-separated."""
    values = checked(dataset)[()]
    return ColumnTable(values, tuple(str(dataset.attrs[names]).split(",")), str(dataset.attrs.get("units", "1")),
                       str(dataset.attrs.get("convention", "")))
