"""Reading YAML input files (subject.yaml, pipelines, study files) with one-line errors."""

from __future__ import annotations

from pathlib import Path

import yaml

from gaitcli.errors import InputError


def read_yaml(path: str | Path):
    """Parse a YAML file; a file that is not UTF-8 text or not YAML is an :class:`InputError`."""
    try:
        return yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(path, None, "not a text file (expected UTF-8 YAML)") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise InputError(path, f"line {mark.line + 1}" if mark else None, "not valid YAML") from None
