"""Reading YAML input files (subject.yaml, pipelines, study files) with one-line errors.

Untrusted files are read with bounded cost and without surprises:

- at most ``MAX_YAML_BYTES`` (1 MB: a subject or pipeline file is a few hundred bytes);
- aliases may expand the document to at most ``MAX_EXPANDED_NODES`` nodes (an "alias bomb" of 300 bytes
  expands to billions);
- a key given twice in one mapping is an error (PyYAML silently keeps the last);
- control characters (NUL, ESC, BEL, form feed) and integers of more than ``MAX_INTEGER_CHARACTERS`` are
  errors naming the line;
- numbers as YAML 1.2 reads them: ``1e12`` and ``1.0e12`` are floats (YAML 1.1 wants ``1.0e+12``).
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from gaitcli.errors import InputError, shown

MAX_YAML_BYTES = 1_000_000
MAX_EXPANDED_NODES = 10_000
#: the longest integer read (Python converts at most 4300 digits; a validator says more about shorter ones)
MAX_INTEGER_CHARACTERS = 1000

# YAML 1.2 core-schema floats that YAML 1.1 reads as strings: an exponent without a sign or without a dot
_FLOAT_1_2 = re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$")


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader with duplicate keys refused and YAML 1.2 exponents."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, (str, int, float, bool)) or key is None:
                if key in seen:
                    raise _Duplicate(key, key_node.start_mark)
                seen.add(key)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node):
        if len(node.value) > MAX_INTEGER_CHARACTERS:  # int() refuses more than 4300 digits (ValueError)
            raise _TooLong(node.value, node.start_mark)
        return super().construct_yaml_int(node)


_Loader.add_constructor("tag:yaml.org,2002:int", _Loader.construct_yaml_int)


_Loader.add_implicit_resolver("tag:yaml.org,2002:float", _FLOAT_1_2, list("-+0123456789."))


class _TooLong(Exception):
    def __init__(self, value, mark):
        self.value, self.mark = value, mark


class _Duplicate(Exception):
    def __init__(self, key, mark):
        self.key, self.mark = key, mark


def _expanded_size(node, sizes: dict, limit: int) -> int:
    """Nodes in the document with every alias expanded (shared nodes counted at each use), stopping past
    ``limit``."""
    key = id(node)
    if key in sizes:
        return sizes[key]
    if isinstance(node, yaml.SequenceNode):
        children = node.value
    elif isinstance(node, yaml.MappingNode):
        children = [n for pair in node.value for n in pair]
    else:
        children = []
    total = 1
    for child in children:
        total += _expanded_size(child, sizes, limit)
        if total > limit:
            break
    sizes[key] = total
    return total


def read_yaml(path: str | Path):
    """Parse a YAML file (module docstring for the limits); any problem is an :class:`InputError`."""
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_YAML_BYTES:
            raise InputError(path, None, f"{size:,} bytes (expected a YAML file of at most {MAX_YAML_BYTES:,} bytes)")
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise InputError(path, None, "not a text file (expected UTF-8 YAML)") from None
    except PermissionError:
        raise InputError(path, None, "cannot be read (permission denied)") from None
    except IsADirectoryError:
        raise InputError(path, None, "is a folder (expected a YAML file)") from None
    try:
        loader = _Loader(text)
    except yaml.reader.ReaderError as exc:  # PyYAML's own message spans two lines
        line = text.count("\n", 0, exc.position) + 1
        raise InputError(path, f"line {line}", f"control character U+{exc.character:04X} "
                                                 "(expected printable text)") from None
    try:
        node = loader.get_single_node()
        if node is not None and _expanded_size(node, {}, MAX_EXPANDED_NODES) > MAX_EXPANDED_NODES:
            raise InputError(path, None, f"its aliases expand it beyond {MAX_EXPANDED_NODES:,} values "
                                         "(expected a plain document)")
        return None if node is None else loader.construct_document(node)
    except _Duplicate as dup:
        raise InputError(path, f"line {dup.mark.line + 1}",
                         f"key {shown(dup.key)} given twice (expected each key once)") from None
    except _TooLong as long:
        raise InputError(path, f"line {long.mark.line + 1}", f"an integer of {len(long.value):,} characters "
                                                             f"(expected at most {MAX_INTEGER_CHARACTERS:,})") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise InputError(path, f"line {mark.line + 1}" if mark else None, "not valid YAML") from None
    except RecursionError:
        raise InputError(path, None, "nested too deeply (expected a plain document)") from None
    finally:
        loader.dispose()
