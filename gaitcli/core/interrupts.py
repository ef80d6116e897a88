"""Interrupts (Ctrl-C, SIGTERM) that stop a run and write nothing.

The CLI turns SIGTERM into the same ``KeyboardInterrupt`` as Ctrl-C (:func:`terminate_as_interrupt`) and
answers both with "gait: interrupted", exit 130. Outputs are staged and renamed into place only when
complete, so an interrupt anywhere leaves the earlier results as they were.

IPOPT needs :func:`interrupts_raised`: CasADi stops the solver on a KeyboardInterrupt but then returns its
iterate as an ordinary failure ("NonIpopt_Exception_Thrown"), which a stage would report as unconverged
and write as its result.
"""

from __future__ import annotations

import ctypes
import os
import signal
import threading
from contextlib import contextmanager

#: the signals that interrupt a run
INTERRUPTS = (signal.SIGINT, signal.SIGTERM)


def _interrupt_in(owner_pid: int):
    """A handler raising KeyboardInterrupt in process ``owner_pid``; in a process forked from it (a worker
    signalled before :func:`as_worker` set its own handlers) it ends that process at once, printing nothing."""
    def handler(signum, frame):
        if os.getpid() != owner_pid:
            os._exit(128 + signum)
        raise KeyboardInterrupt

    return handler


@contextmanager
def terminate_as_interrupt():
    """Within it SIGTERM raises KeyboardInterrupt, as Ctrl-C does (main thread only; elsewhere nothing
    changes); the previous handler is restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _interrupt_in(os.getpid()))
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def _interrupts_to(handler):
    """Within it SIGINT and SIGTERM go to ``handler(signum)``; after it the previous handlers are back and,
    if either came, KeyboardInterrupt is raised (main thread only; elsewhere nothing changes)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    interrupted = []

    def on_interrupt(signum, frame):
        interrupted.append(signum)
        handler(signum)

    previous = {s: signal.signal(s, on_interrupt) for s in INTERRUPTS}
    try:
        yield
    finally:
        for s, restored in previous.items():
            signal.signal(s, restored)
    if interrupted:
        raise KeyboardInterrupt


def _raise_interrupt(signum):
    raise KeyboardInterrupt  # what stops IPOPT (CasADi checks for it between iterations)


def interrupts_raised():
    """Run a solver so that an interrupt during it raises KeyboardInterrupt once the solver returns, whatever
    the solver made of it (see the module docstring)."""
    return _interrupts_to(_raise_interrupt)


def interrupts_deferred():
    """Within it an interrupt waits: it raises KeyboardInterrupt when the block ends (main thread only). For
    a short step that must not stop half-way, such as starting the workers a run will have to stop."""
    return _interrupts_to(lambda signum: None)


#: prctl's option that has the kernel signal a process when its parent dies (linux/prctl.h)
_PR_SET_PDEATHSIG = 1


def end_with_parent(parent_pid: int | None = None) -> None:
    """In a child process: on Linux, have the kernel SIGKILL it when its parent dies (PR_SET_PDEATHSIG), however
    the parent dies (SIGKILL included), so that no worker or reader is left behind. ``parent_pid``: the parent's
    pid before the fork; a parent that died before the call ends the child now. Elsewhere nothing."""
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(_PR_SET_PDEATHSIG, signal.SIGKILL)
    except (OSError, AttributeError):
        return
    if parent_pid is not None and os.getppid() != parent_pid:
        os._exit(1)


def _exit_quietly(signum, frame):
    raise SystemExit(128 + signum)


def as_worker(parent_pid: int) -> None:
    """A worker process's initializer: it ends with its parent (:func:`end_with_parent`) and leaves interrupts
    to it. Ctrl-C, which reaches the whole process group, is ignored outside a solve (:func:`interrupts_raised`
    still stops one); SIGTERM, how the parent ends a worker, unwinds it as SystemExit, which neither prints a
    traceback when the worker is idle nor leaves a temporary folder behind."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # first: an exception in an initializer is logged
    signal.signal(signal.SIGTERM, _exit_quietly)
    end_with_parent(parent_pid)
