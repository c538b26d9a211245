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
"""

from __future__ import annotations

import itertools
import os
import signal
import sys
import threading
from types import FrameType


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
