"""Progress bars for long work (frames, optimizer iterations, trials), on stderr via rich."""

from __future__ import annotations

from contextlib import contextmanager


class _Silent:
    def advance(self, steps: float = 1) -> None:
        pass

    def update(self, **kwargs) -> None:
        pass


class _Bar:
    def __init__(self, progress, task):
        self._progress = progress
        self._task = task

    def advance(self, steps: float = 1) -> None:
        self._progress.advance(self._task, steps)

    def update(self, **kwargs) -> None:
        self._progress.update(self._task, **kwargs)


@contextmanager
def progress_bar(description: str, *, total: int | None = None, enabled: bool = True):
    """Yield an object with ``advance()``/``update()``; silent when disabled or stderr is not a terminal."""
    import sys

    if not enabled or not sys.stderr.isatty():
        yield _Silent()
        return
    from rich.console import Console
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                  TimeElapsedColumn(), console=Console(stderr=True), transient=True) as progress:
        yield _Bar(progress, progress.add_task(description, total=total))
