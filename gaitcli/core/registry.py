"""The stage registry: what a stage is to the pipeline, the CLI and a batch runner.

A stage declares its name, its config dataclass (defined beside the stage),
the stages whose results it takes (``depends``), the stages whose output it may
ask for (``optional``: read back where fresh, else made first, and only with a
trial; ``StageContext.optional``), whether it needs a trial at all (``trial``),
and four functions:

- ``run(context, cfg) -> result``: pure computation from the context (subject,
  trial files, the earlier stages' hand-offs) to a typed result; raises
  :class:`~gaitcli.errors.InputError` for bad input;
- ``write(folder, result, attrs) -> summary``: the stage's files into a fresh
  folder (CSV, HDF5 with ``attrs`` at its root); the pipeline adds ``summary.json``.
  Default (``write=None``): the result dataclass as one HDF5 record and its
  scalar fields as the summary;
- ``read(h5_path) -> hand-off``: what later stages need, read back from the HDF5
  (default: the ``result`` record as the ``result`` type);
- ``plots(h5_path, folder, title)``: figures rendered from the HDF5 (optional).

``handoff(result)`` gives the same hand-off from a result in memory, so a later
stage sees one type whether its input was computed in this run or read back.
Stages are registered in ``gaitcli/run/stages.py`` (one entry per stage) and run by
:func:`gaitcli.run.pipeline.run_stages`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from gaitcli.core.validate import one_of


def _identity(result):
    return result


def _converged(result) -> bool:
    return bool(getattr(result, "converged", True))


@dataclass(frozen=True)
class Progress:
    """A progress report from a running stage: ``completed`` of ``total`` steps (None: unknown); ``detail`` what
    the step reached (e.g. an optimizer's objective), shown beside the description."""

    stage: str
    description: str
    completed: float = 0.0
    total: float | None = None
    detail: str = ""


ProgressCallback = Callable[[Progress], None]


def no_progress(report: Progress) -> None:
    """The progress callback that reports nothing."""


@dataclass
class StageContext:
    """What a stage's ``run`` is given besides its configuration.

    ``subject``: the validated subject.yaml; paths of the trial's files (for
    messages); ``inputs[name]``: the hand-off of each stage it depends on, and
    ``input_paths[name]`` where it came from (the HDF5 it was read from, or the
    trial file when it was computed in this run);
    ``recording()`` and ``static_recording()``: the dynamic trial as read and the
    standing trial (None without static.c3d), labels renamed by the marker set;
    ``progress``: where to report progress. ``files``: the files named for this
    run by name (e.g. predict's ``reference`` and ``init``; ``subject`` has taken
    the trial's subject's place); ``workers``, ``scheduler``: where a stage may run
    work in parallel (:func:`gaitcli.run.cluster.workers`). Without a trial
    (a stage with ``trial=False``) the trial's paths are None and ``recording``
    raises.
    """

    subject: Any
    folder: Path | None
    subject_path: Path | None
    trial_path: Path | None
    static_path: Path | None
    inputs: dict[str, Any]
    input_paths: dict[str, Path | None]
    recording: Callable[[], Any]
    static_recording: Callable[[], Any]
    progress: ProgressCallback = no_progress
    stage: str = ""
    files: dict[str, Path] = field(default_factory=dict)
    workers: int | None = None
    scheduler: str | None = None
    #: the pipeline's: an optional stage's hand-off (None without a trial), and the record of a file read
    resolve_optional: Callable[[str], Any] = lambda name: None
    record_input: Callable[[Path], None] = lambda path: None

    def report(self, description: str, completed: float = 0.0, total: float | None = None) -> None:
        self.progress(Progress(self.stage, description, completed, total))

    def optional(self, name: str) -> Any:
        """The hand-off of ``name``, one of the stage's ``optional`` stages: read back from its output where
        that is fresh, else made (and written) first; its output's path is then ``input_paths[name]``. None
        without a trial."""
        return self.resolve_optional(name)

    def uses(self, path: Path) -> Path:
        """``path``, recorded as an input of this stage (its SHA-256 in the HDF5 attributes)."""
        self.record_input(Path(path))
        return Path(path)


@dataclass(frozen=True)
class Stage:
    """One processing stage (see the module docstring)."""

    name: str
    config: type
    run: Callable[[StageContext, Any], Any]
    h5_name: str
    depends: tuple[str, ...] = ()
    #: stages whose output it may ask for with ``StageContext.optional`` (module docstring)
    optional: tuple[str, ...] = ()
    #: whether it needs a trial; a stage that does not runs without one (a prediction from defaults)
    trial: bool = True
    result: type | None = None  # the result dataclass (for the default writer and reader)
    write: Callable[[Path, Any, dict], dict] | None = None
    read: Callable[[Path], Any] | None = None
    handoff: Callable[[Any], Any] = _identity
    plots: Callable[[Path, Path, str], list] | None = None
    #: output folder below the output root, from the stage's config (default: the stage's name)
    folder: Callable[[Any], str] | None = None
    converged: Callable[[Any], bool] = _converged
    #: the one-line reason an unconverged result gives (exit 3)
    unconverged: Callable[[Any], str] = field(default=lambda result: "did not converge")
    #: the result in a few words, from the stage's summary.json (the command line's line for it)
    describe: Callable[[dict], str] = field(default=lambda summary: "")

    def output_folder(self, cfg) -> str:
        return self.name if self.folder is None else self.folder(cfg)


_REGISTRY: dict[str, Stage] = {}


def register(stage: Stage) -> Stage:
    """Add ``stage`` to the registry (after the stages it depends on); returns it."""
    for dep in stage.depends:
        one_of(dep, tuple(_REGISTRY), where=f"stage {stage.name}: depends")
    for dep in stage.optional:
        one_of(dep, tuple(_REGISTRY), where=f"stage {stage.name}: optional")
    _REGISTRY[stage.name] = stage
    return stage


def unregister(name: str) -> None:
    """Remove a stage (tests register throwaway stages)."""
    _REGISTRY.pop(name, None)


def stage(name: str) -> Stage:
    """The registered stage ``name`` (the built-in ones are registered by importing ``gaitcli.run.stages``)."""
    if not _REGISTRY:
        raise LookupError("no stage registered yet: import gaitcli.run.stages (or gaitcli.run.config) first")
    return _REGISTRY[one_of(name, tuple(_REGISTRY), where="stage")]


def stage_names() -> tuple[str, ...]:
    """Registered stages in registration order (every stage after the stages it depends on)."""
    return tuple(_REGISTRY)


def requirements(name: str) -> tuple[str, ...]:
    """``name`` and every stage it depends on, directly or not, in registry order."""
    needed = set()

    def visit(n):
        if n not in needed:
            needed.add(n)
            for dep in stage(n).depends:
                visit(dep)
    visit(name)
    return tuple(n for n in _REGISTRY if n in needed)
