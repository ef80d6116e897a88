"""The command line's progress display for long work (stages, optimizer iterations, trials), on stderr via rich.

Only :mod:`gaitcli.cli` uses it: the code that runs stages reports progress through callbacks
(:class:`gaitcli.core.registry.Progress`, a batch's rows) and never draws.
"""

from __future__ import annotations

import sys


def _bars(count: str):
    """A started rich display on stderr: description, bar, ``count`` (a rich format of the task), elapsed time."""
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    progress = Progress(TextColumn("{task.description}"), BarColumn(), TextColumn(count), TimeElapsedColumn(),
                        console=Console(stderr=True), transient=True)
    progress.start()
    return progress


class ProgressDisplay:
    """A progress callback for :func:`gaitcli.run.pipeline.run_stages`: one rich bar per stage and description.

    Silent when disabled or when stderr is not a terminal. Use as a context manager.
    """

    def __init__(self, *, enabled: bool = True):
        self.enabled = enabled and sys.stderr.isatty()
        self._progress = None
        self._tasks: dict[tuple[str, str], int] = {}

    def __enter__(self) -> ProgressDisplay:
        if self.enabled:
            self._progress = _bars("{task.completed}/{task.total}")
        return self

    def __exit__(self, *exc) -> None:
        if self._progress is not None:
            self._progress.stop()

    def __call__(self, report) -> None:
        if self._progress is None:
            return
        key = (report.stage, report.description)
        if key not in self._tasks:
            self._tasks[key] = self._progress.add_task(report.description, total=report.total)
        label = f"{report.description} {report.detail}" if getattr(report, "detail", "") else report.description
        self._progress.update(self._tasks[key], completed=report.completed, total=report.total, description=label)


class BatchProgress:
    """``gait batch``'s display: one rich bar per stage, trials done out of all, with ok / failed / skipped counts.

    Silent when disabled or when stderr is not a terminal. Use as a context manager; call with a trial's rows.
    """

    def __init__(self, stages, *, enabled: bool = True):
        self.stages = tuple(stages)
        self.enabled = enabled and sys.stderr.isatty()
        self._progress = None
        self._tasks: dict[str, int] = {}
        self._counts = {s: {"ok": 0, "failed": 0, "skipped": 0, "unconverged": 0} for s in self.stages}

    def __enter__(self) -> BatchProgress:
        if self.enabled:
            self._progress = _bars("{task.completed}/{task.total} trials")
        return self

    def __exit__(self, *exc) -> None:
        if self._progress is not None:
            self._progress.stop()

    def start(self, trials: int) -> None:
        if self._progress is not None:
            self._tasks = {s: self._progress.add_task(self._label(s), total=trials) for s in self.stages}

    def _label(self, stage: str) -> str:
        c = self._counts[stage]
        return f"{stage:8s} {c['ok']} ok, {c['failed']} failed, {c['skipped']} skipped"

    def __call__(self, rows) -> None:
        for row in rows:
            if row.stage not in self._counts:
                continue
            self._counts[row.stage][row.status] += 1
            if self._progress is not None and row.stage in self._tasks:
                self._progress.update(self._tasks[row.stage], advance=1, description=self._label(row.stage))
