"""Progress display for long work (stages, optimizer iterations, trials), on stderr via rich."""

from __future__ import annotations

import sys


class ProgressDisplay:
    """A progress callback for :func:`gaitcli.pipeline.run_stages`: one rich bar per stage and description.

    Silent when disabled or when stderr is not a terminal. Use as a context manager.
    """

    def __init__(self, *, enabled: bool = True):
        self.enabled = enabled and sys.stderr.isatty()
        self._progress = None
        self._tasks: dict[tuple[str, str], int] = {}

    def __enter__(self) -> ProgressDisplay:
        if self.enabled:
            from rich.console import Console
            from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

            self._progress = Progress(TextColumn("{task.description}"), BarColumn(),
                                      TextColumn("{task.completed}/{task.total}"), TimeElapsedColumn(),
                                      console=Console(stderr=True), transient=True)
            self._progress.start()
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
