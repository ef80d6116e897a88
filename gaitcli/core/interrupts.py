"""Interrupts (Ctrl-C, SIGTERM) that stop a run and write nothing.

The CLI turns SIGTERM into the same ``KeyboardInterrupt`` as Ctrl-C (:func:`terminate_as_interrupt`) and
answers both with "gait: interrupted", exit 130. Outputs are staged and renamed into place only when
complete, so an interrupt anywhere leaves the earlier results as they were.

IPOPT needs :func:`interrupts_raised`: CasADi stops the solver on a KeyboardInterrupt but then returns its
iterate as an ordinary failure ("NonIpopt_Exception_Thrown"), which a stage would report as unconverged
and write as its result.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

#: the signals that interrupt a run
INTERRUPTS = (signal.SIGINT, signal.SIGTERM)


def _raise_interrupt(signum, frame):
    raise KeyboardInterrupt


@contextmanager
def terminate_as_interrupt():
    """Within it SIGTERM raises KeyboardInterrupt, as Ctrl-C does (main thread only; elsewhere nothing
    changes); the previous handler is restored after."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGTERM, _raise_interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


@contextmanager
def interrupts_raised():
    """Run a solver so that an interrupt during it raises KeyboardInterrupt once the solver returns, whatever
    the solver made of it (see the module docstring)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    interrupted = []

    def on_interrupt(signum, frame):
        interrupted.append(signum)
        raise KeyboardInterrupt  # what stops IPOPT (CasADi checks for it between iterations)

    previous = {s: signal.signal(s, on_interrupt) for s in INTERRUPTS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    if interrupted:
        raise KeyboardInterrupt
