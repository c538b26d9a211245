"""Stop signals honoured from a command's first instant (below every layer).

A program started in the background by a script (``cmd &``) inherits SIGINT ignored, and
Python then never installs its KeyboardInterrupt handler: a SIGINT in the first seconds of
`hetros launch` (before the launcher installs its own) was lost, and the launch ran to its
end with exit 0; a Ctrl-C while Python imported hetros printed a traceback. ``hetros`` calls
:func:`honour_stop_signals` before it imports anything heavy: SIGINT and SIGTERM then end the
process at once, quietly, with 130 and 143. That holds for `hetros launch` until its launcher
installs handlers of its own (nothing has started before: no process, no shared memory),
since a KeyboardInterrupt raised in the middle of an import can surface as another error. A
command that has something to finish (a recording's index) makes SIGINT a KeyboardInterrupt
again (:func:`interruptible`) as soon as it runs.

The kernel may deliver a signal sent to a process to any of its threads, and CPython runs the
Python handler only in the main thread, between two bytecodes. A main thread blocked in an
untimed wait never gets there when the signal landed on another thread: a `hetros master` then
outlived its SIGTERM, and a launch its Ctrl-C. A main thread that waits for something else
therefore waits in slices (:func:`wait_until_set`, :func:`next_item`), which bounds the delay.
"""

from __future__ import annotations

import itertools
import os
import queue
import signal
import sys
import threading
import time
from types import FrameType
from typing import TypeVar

_Item = TypeVar("_Item")

SIGNAL_SLICE = 0.2  # seconds a stop signal that reached another thread waits, at most, for its handler


def _exit_now(signum: int, _frame: FrameType | None) -> None:
    os._exit(128 + signum)


def is_command_line() -> bool:
    """Whether this process is the ``hetros`` command (its console script, or ``python -m hetros``)."""
    argv = list(getattr(sys, "orig_argv", sys.argv))  # [python, the script or -m ..., ...]
    if any(os.path.basename(arg) == "hetros" for arg in argv[:2]):
        return True
    return any(a == "-m" and b in ("hetros", "hetros.cli") for a, b in itertools.pairwise(argv))


def honour_stop_signals() -> None:
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _exit_now)


def interruptible() -> None:
    """SIGINT as Python's KeyboardInterrupt (for a command that stops in order by catching it)."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)


def wait_until_set(event: threading.Event) -> None:
    """``event.wait()``, during which a stop signal's handler still runs (see the module's docstring)."""
    while not event.wait(SIGNAL_SLICE):
        pass


def next_item(items: queue.Queue[_Item], timeout: float | None = None) -> _Item:
    """``items.get(timeout=timeout)`` (``queue.Empty`` when it runs out), during which a stop signal's
    handler still runs (see the module's docstring)."""
    end = None if timeout is None else time.monotonic() + timeout
    while True:
        left = SIGNAL_SLICE if end is None else min(SIGNAL_SLICE, end - time.monotonic())
        try:
            return items.get(timeout=max(left, 0.0))
        except queue.Empty:
            if end is not None and time.monotonic() >= end:
                raise
