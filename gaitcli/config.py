"""Pipeline YAML → validated, frozen dataclasses with defaults.

Every stage parameter has a default; unknown keys are errors (with a "did you
mean"); CLI options override the file via :func:`with_overrides`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from gaitcli.errors import InputError

STAGES = ("filter", "idyn", "muscles")


@dataclass(frozen=True)
class FilterConfig:
    """Parameters of ``gait filter`` (3.1.4)."""

    cutoff_hz: float = 6.0  # net cut-off of the zero-lag cascade for markers (0: no filtering)
    force_cutoff_hz: float = 6.0  # the same for force-plate signals, before COP is formed
    order: int = 2  # Butterworth order of one pass
    max_gap_frames: int = 10  # longer marker gaps stay NaN
    force_threshold_N: float = 20.0  # COP/free moment only above this vertical load


@dataclass(frozen=True)
class IdynConfig:
    """Parameters of ``gait idyn`` (3.2–3.4)."""

    frames: str = "reference"  # 'reference' or 'anatomical': frames the joint moments are expressed in
    gravity_m_s2: float = 9.81


@dataclass(frozen=True)
class MusclesConfig:
    """Parameters of ``gait muscles`` (ch. 4)."""

    method: str = "eid"  # so | mso | eid
    side: str = "r"  # r | l
    nodes: int = 50
    validate: bool = False
    objective: str = "metabolic"  # EID objective: metabolic | crowninshield_brand
    phase: str = "cycle"  # cycle: a full stride recorded on the plates (periodic); swing: one swing phase


@dataclass(frozen=True)
class PipelineConfig:
    """A whole pipeline: which stages ``gait run`` performs and each stage's parameters."""

    stages: tuple[str, ...] = ("filter", "idyn")
    filter: FilterConfig = field(default_factory=FilterConfig)
    idyn: IdynConfig = field(default_factory=IdynConfig)
    muscles: MusclesConfig = field(default_factory=MusclesConfig)


CHOICES = {
    ("idyn", "frames"): ("reference", "anatomical"),
    ("muscles", "method"): ("so", "mso", "eid"),
    ("muscles", "side"): ("r", "l"),
    ("muscles", "objective"): ("metabolic", "crowninshield_brand"),
    ("muscles", "phase"): ("cycle", "swing"),
}
NON_NEGATIVE = {("filter", "cutoff_hz"), ("filter", "force_cutoff_hz")}  # 0 turns the filter off
POSITIVE = {("filter", "order"),
            ("filter", "force_threshold_N"), ("idyn", "gravity_m_s2"), ("muscles", "nodes")}


def _unknown(path, where: str, key: str, allowed) -> InputError:
    hint = difflib.get_close_matches(key, list(allowed), n=1)
    more = f" (did you mean '{hint[0]}'?)" if hint else ""
    return InputError(path, f"{where}{key}", f"unknown key{more}; allowed keys are {', '.join(allowed)}")


def _coerce(path, section: str, name: str, default: Any, value: Any) -> Any:
    where = f"{section}.{name}"
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise InputError(path, where, f"got {value!r} (expected true or false)")
        return value
    if isinstance(default, int):
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(path, where, f"got {value!r} (expected an integer)")
    elif isinstance(default, float):
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise InputError(path, where, f"got {value!r} (expected a finite number)")
        value = float(value)
    elif isinstance(default, str):
        if not isinstance(value, str):
            raise InputError(path, where, f"got {value!r} (expected text)")
        choices = CHOICES.get((section, name))
        if choices and value not in choices:
            raise InputError(path, where, f"got {value!r} (expected one of {', '.join(choices)})")
    if (section, name) in POSITIVE and value <= 0:
        raise InputError(path, where, f"got {value!r} (expected a value > 0)")
    if (section, name) in NON_NEGATIVE and value < 0:
        raise InputError(path, where, f"got {value!r} (expected a cut-off ≥ 0 Hz; 0 turns the filter off)")
    if name == "max_gap_frames" and value < 0:
        raise InputError(path, where, f"got {value!r} (expected an integer ≥ 0)")
    return value


def _section(path, name: str, cls, data: Any):
    if data is None:
        return cls()
    if not isinstance(data, dict):
        raise InputError(path, name, f"got {type(data).__name__} (expected a mapping of parameters)")
    defaults = cls()
    known = [f.name for f in dataclasses.fields(cls)]
    values = {}
    for key, value in data.items():
        if key not in known:
            raise _unknown(path, f"{name}.", str(key), known)
        values[key] = _coerce(path, name, key, getattr(defaults, key), value)
    return dataclasses.replace(defaults, **values)


def pipeline_from_dict(data: dict | None, path: str | Path | None = None) -> PipelineConfig:
    """Validate a pipeline mapping (as read from YAML) into a :class:`PipelineConfig`."""
    data = data or {}
    if not isinstance(data, dict):
        raise InputError(path, None, "expected a YAML mapping with stage sections")
    sections = {"filter": FilterConfig, "idyn": IdynConfig, "muscles": MusclesConfig}
    for key in data:
        if key not in ("stages", *sections):
            raise _unknown(path, "", str(key), ["stages", *sections])
    stages = data.get("stages", PipelineConfig.stages)
    if not isinstance(stages, (list, tuple)) or not stages or not all(s in STAGES for s in stages):
        raise InputError(path, "stages", f"got {stages!r} (expected a non-empty list drawn from {', '.join(STAGES)})")
    order = [s for s in STAGES if s in stages]
    return PipelineConfig(stages=tuple(order),
                          **{name: _section(path, name, cls, data.get(name)) for name, cls in sections.items()})


def read_yaml(path: Path):
    """Parse a YAML file; a file that is not UTF-8 text or not YAML is an :class:`InputError`."""
    try:
        return yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(path, None, "not a text file (expected UTF-8 YAML)") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        raise InputError(path, f"line {mark.line + 1}" if mark else None, "not valid YAML") from None


def load_pipeline(path: str | Path | None = None) -> PipelineConfig:
    """Read a pipeline YAML file; ``None`` gives the built-in defaults (``pipelines/standard.yaml``)."""
    if path is None:
        return PipelineConfig()
    path = Path(path)
    if not path.is_file() and path.suffix == "" and len(path.parts) == 1:  # a bundled pipeline by name
        from gaitcli.resources import bundled_pipelines, pipeline_file

        if str(path) in bundled_pipelines():
            path = pipeline_file(str(path))
        else:
            raise InputError(path, None, f"pipeline file not found (bundled pipelines: "
                                         f"{', '.join(bundled_pipelines())})")
    if not path.is_file():
        raise InputError(path, None, "pipeline file not found")
    data = read_yaml(path)
    return pipeline_from_dict(data, path)


def with_overrides(cfg: PipelineConfig, section: str, **options) -> PipelineConfig:
    """Return ``cfg`` with the given options of one section replaced (``None`` = keep the file's value)."""
    given = {k: v for k, v in options.items() if v is not None}
    if not given:
        return cfg
    current = getattr(cfg, section)
    merged = {**dataclasses.asdict(current), **given}
    new = _section("command line", section, type(current), merged)
    return dataclasses.replace(cfg, **{section: new})


def to_yaml(cfg: PipelineConfig) -> str:
    """The resolved configuration as YAML (stored in every HDF5 file's attributes)."""
    data = dataclasses.asdict(cfg)
    data["stages"] = list(cfg.stages)
    return yaml.safe_dump(data, sort_keys=False)
