"""Pipeline YAML → validated, frozen configuration assembled from the stage registry.

A pipeline file has ``stages:`` (which stages ``gait run`` performs) and one
section per registered stage with that stage's parameters (its config
dataclass, defined beside the stage). Every parameter has a default; unknown
keys are errors (with a "did you mean"); CLI options override the file via
:func:`with_overrides`.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from gaitcli.core.registry import stage, stage_names
from gaitcli.core.validate import known_keys, replace_checked
from gaitcli.errors import InputError, shown
from gaitcli.io.yamlfile import read_yaml
from gaitcli.run import stages as _builtin_stages  # noqa: F401  (registers the built-in stages)

#: what ``gait run`` does without a pipeline file (``pipelines/standard.yaml``)
DEFAULT_STAGES = ("filter", "idyn")


def _default_sections() -> dict[str, Any]:
    return {name: stage(name).config() for name in stage_names()}


@dataclass(frozen=True)
class PipelineConfig:
    """A whole pipeline: which stages ``gait run`` performs and each registered stage's parameters.

    ``cfg.filter``, ``cfg.idyn``, … are the sections by stage name.
    """

    stages: tuple[str, ...] = DEFAULT_STAGES
    sections: Mapping[str, Any] = field(default_factory=_default_sections)

    def __getattr__(self, name: str):
        sections = self.__dict__.get("sections", {})
        if name in sections:
            return sections[name]
        raise AttributeError(name)

    def section(self, name: str):
        return self.sections[name]

    def replace_section(self, name: str, value) -> PipelineConfig:
        return dataclasses.replace(self, sections={**self.sections, name: value})


def _section(path, name: str, data: Any):
    defaults = stage(name).config()
    if data is None:
        return defaults
    if not isinstance(data, dict):
        raise InputError(path, name, f"got {type(data).__name__} (expected a mapping of parameters)")
    return replace_checked(defaults, data, section=name, path=path)


def pipeline_from_dict(data: dict | None, path: str | Path | None = None) -> PipelineConfig:
    """Validate a pipeline mapping (as read from YAML) into a :class:`PipelineConfig`."""
    data = data or {}
    if not isinstance(data, dict):
        raise InputError(path, None, "expected a YAML mapping with stage sections")
    names = stage_names()
    known_keys(data, ("stages", *names), path=path)
    chosen = data.get("stages", DEFAULT_STAGES)
    if not isinstance(chosen, (list, tuple)) or not chosen or not all(s in names for s in chosen):
        raise InputError(path, "stages",
                         f"got {shown(chosen)} (expected a non-empty list drawn from {', '.join(names)})")
    return PipelineConfig(stages=tuple(s for s in names if s in chosen),
                          sections={name: _section(path, name, data.get(name)) for name in names})


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
    return pipeline_from_dict(read_yaml(path), path)


def with_overrides(cfg: PipelineConfig, section: str, **options) -> PipelineConfig:
    """Return ``cfg`` with the given options of one section replaced (``None`` = keep the file's value)."""
    given = {k: v for k, v in options.items() if v is not None}
    if not given:
        return cfg
    return cfg.replace_section(section, replace_checked(cfg.section(section), given, section=section,
                                                        path="command line"))


def configure(pipeline: Path | None, **sections) -> PipelineConfig:
    """Load the pipeline file (or defaults) and apply the CLI's overrides per section."""
    cfg = load_pipeline(pipeline)
    for section, options in sections.items():
        cfg = with_overrides(cfg, section, **options)
    return cfg


def section_dict(cfg: PipelineConfig, name: str) -> dict:
    """One section's parameters as plain data (pairs as lists), as a pipeline file would give them."""
    return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(cfg.section(name)).items()}


def to_yaml(cfg: PipelineConfig) -> str:
    """The resolved configuration as YAML (stored in every HDF5 file's attributes)."""
    data = {"stages": list(cfg.stages), **{name: section_dict(cfg, name) for name in cfg.sections}}
    return yaml.safe_dump(data, sort_keys=False)
