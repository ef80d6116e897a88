"""Validators of user input: every problem becomes one :class:`~gaitcli.errors.InputError` line.

Messages name the file, the field and what was expected, e.g.
``pipeline.yaml: muscles.method: got 'eidd' (expected one of so, mso, eid; did you mean 'eid'?)``.

Stage parameters are declared once with :func:`parameter` (default, choices, range,
help, and for values that are not a single number or word the function that parses
them); the pipeline file (``run/config.py``), study files (``run/studies.py``) and the
command line (``cli.py``, whose click types and callbacks come from the same metadata)
all validate with :func:`check_parameter`, which names the file and key, or the flag,
that gave the value.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from gaitcli.errors import InputError, shown

Where = str | Path | None


def _hint(value: Any, allowed: Iterable[str]) -> str:
    match = difflib.get_close_matches(str(value), [str(a) for a in allowed], n=1)
    return f"; did you mean '{match[0]}'?" if match else ""


def expected_one_of(value: Any, allowed: Iterable) -> str:
    """The problem text for a value outside ``allowed``: "got …, expected one of …; did you mean …?"."""
    allowed = tuple(allowed)
    return (f"got {shown(value)} (expected one of {', '.join(map(str, allowed))}"
            f"{_hint(value, allowed) if isinstance(value, str) else ''})")


def one_of(value: Any, allowed: Iterable, *, where: str | None, path: Where = None) -> Any:
    """``value`` if it is one of ``allowed``, else "got …, expected one of …; did you mean …?"."""
    allowed = tuple(allowed)
    if value in allowed:
        return value
    raise InputError(path, where, expected_one_of(value, allowed))


def unknown_key(key: Any, allowed: Iterable[str], *, where: str = "", path: Where = None) -> InputError:
    """The error for a key a mapping may not hold (``where`` is the prefix, e.g. ``"filter."``)."""
    allowed = tuple(allowed)
    return InputError(path, f"{where}{key}", f"unknown key{_hint(key, allowed)}; allowed keys are "
                                             f"{', '.join(allowed)}")


def known_keys(mapping: Mapping, allowed: Iterable[str], *, where: str = "", path: Where = None) -> None:
    """Raise for the first key of ``mapping`` that is not in ``allowed``."""
    allowed = tuple(allowed)
    for key in mapping:
        if key not in allowed:
            raise unknown_key(key, allowed, where=where, path=path)


def number(value: Any, *, where: str | None, path: Where = None, low: float | None = None,
           high: float | None = None, low_open: bool = False, expected: str | None = None) -> float:
    """A finite real number within [low, high] (``low_open``: > low); ``expected`` rewords the message."""
    if low is None and high is None:
        default = "a finite number"
    elif high is None:
        default = f"a number {'>' if low_open else '≥'} {low:g}"
    elif low is None:
        default = f"a number ≤ {high:g}"
    else:
        default = f"a number {'>' if low_open else '≥'} {low:g} and ≤ {high:g}"
    expected = expected or default
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(path, where, f"got {shown(value)} (expected {expected})")
    try:
        value = float(value)
    except OverflowError:  # an integer of hundreds of digits
        raise InputError(path, where, f"got {shown(value)} (expected {expected})") from None
    too_low = low is not None and (value <= low if low_open else value < low)
    if not math.isfinite(value) or too_low or (high is not None and value > high):
        raise InputError(path, where, f"got {value:g} (expected {expected})")
    return value


def integer(value: Any, *, where: str | None, path: Where = None, low: int | None = None,
            high: int | None = None) -> int:
    """An integer within [low, high]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(path, where, f"got {shown(value)} (expected an integer)")
    if (low is not None and value < low) or (high is not None and value > high):
        bounds = (f"between {low} and {high}" if low is not None and high is not None
                  else f"≥ {low}" if low is not None else f"≤ {high}")
        raise InputError(path, where, f"got {shown(value)} (expected an integer {bounds})")
    return value


def boolean(value: Any, *, where: str | None, path: Where = None) -> bool:
    if not isinstance(value, bool):
        raise InputError(path, where, f"got {shown(value)} (expected true or false)")
    return value


def text(value: Any, *, where: str | None, path: Where = None, expected: str = "text") -> str:
    if not isinstance(value, str):
        raise InputError(path, where, f"got {shown(value)} (expected {expected})")
    return value


def number_pair(value: Any, *, fractions: bool = False) -> tuple[float, float]:
    """Two finite numbers from text "A,B" (the command line) or a list of two (a YAML file); with ``fractions``
    each may be a fraction such as "4/3", read exactly (``fractions.Fraction``). ValueError otherwise."""
    from fractions import Fraction

    items = value.split(",") if isinstance(value, str) else value
    if not isinstance(items, (list, tuple)) or len(items) != 2:
        raise ValueError("two numbers")

    def one(item) -> float:
        if isinstance(item, bool):
            raise ValueError("a number")
        if isinstance(item, str):
            try:
                item = Fraction(item.strip()) if fractions else float(item)
            except ZeroDivisionError:
                raise ValueError("a number") from None
        if not isinstance(item, (int, float, Fraction)):
            raise ValueError("a number")
        try:
            number = float(item)
        except OverflowError:
            raise ValueError("a number") from None
        if not math.isfinite(number):
            raise ValueError("a finite number")
        return number

    return one(items[0]), one(items[1])


def parameter(default: Any, *, choices: Iterable | None = None, low: float | None = None,
              high: float | None = None, low_open: bool = False, help: str = "", parse=None,
              expected: str = "", metavar: str | None = None):
    """A stage-config field: its default, allowed values or range, the help text the CLI shows, and for a value
    that is not one number, flag or word, ``parse(value) -> value`` (text from the command line, or what a YAML
    file holds), which raises ValueError when the value is not ``expected`` (or an InputError naming a file it
    read). For a number, ``parse`` checks further what its type and range let through (e.g. parity)."""
    meta = {"choices": None if choices is None else tuple(choices), "low": low, "high": high,
            "low_open": low_open, "help": help, "parse": parse, "expected": expected, "metavar": metavar}
    return dataclasses.field(default=default, metadata={"gait": meta})


def parameter_spec(f: dataclasses.Field) -> dict:
    """The validation metadata of a config field declared with :func:`parameter` (empty limits otherwise)."""
    return f.metadata.get("gait", {"choices": None, "low": None, "high": None, "low_open": False, "help": "",
                                   "parse": None, "expected": "", "metavar": None})


def _parsed(spec: dict, value: Any, *, where: str, path: Where) -> Any:
    try:
        return spec["parse"](value)
    except ValueError:
        raise InputError(path, where, f"got {shown(value)} (expected {spec['expected']})") from None
    except InputError as exc:  # a file the value names: where it was named, and that file
        if path is None or exc.path is None:
            raise InputError(exc.path or path, where, exc.problem) from None
        raise InputError(path, where, f"{shown(str(exc.path))}: {exc.problem}") from None


def check_parameter(f: dataclasses.Field, value: Any, *, where: str, path: Where = None) -> Any:
    """Validate and coerce ``value`` for the config field ``f`` (type from its default, limits from its spec);
    an error names ``path`` and ``where`` (a file and its key, or ``path`` None and the flag)."""
    spec = parameter_spec(f)
    default = f.default
    if isinstance(default, bool):
        return boolean(value, where=where, path=path)
    if isinstance(default, (int, float)):
        if isinstance(default, int):
            low = None if spec["low"] is None else int(spec["low"]) + (1 if spec["low_open"] else 0)
            high = None if spec["high"] is None else int(spec["high"])
            value = integer(value, where=where, path=path, low=low, high=high)
        else:
            value = number(value, where=where, path=path, low=spec["low"], high=spec["high"],
                           low_open=spec["low_open"])
        return value if spec.get("parse") is None else _parsed(spec, value, where=where, path=path)
    if spec.get("parse") is not None:
        return _parsed(spec, value, where=where, path=path)
    if isinstance(default, str):
        value = text(value, where=where, path=path)
        if spec["choices"] is not None:
            one_of(value, spec["choices"], where=where, path=path)
        return value
    return value


def replace_checked(config, values: Mapping[str, Any], *, section: str | None, path: Where = None):
    """``config`` (a frozen dataclass) with ``values`` validated and replaced; unknown keys are errors. Errors
    name ``section.key`` (a pipeline file's), or the key alone without ``section`` (a study file's)."""
    prefix = f"{section}." if section else ""
    fields = {f.name: f for f in dataclasses.fields(config)}
    known_keys(values, fields, where=prefix, path=path)
    checked = {k: check_parameter(fields[k], v, where=f"{prefix}{k}", path=path) for k, v in values.items()}
    return dataclasses.replace(config, **checked)
