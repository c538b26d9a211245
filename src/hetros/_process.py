"""Processes of this machine, as hetros checks on them (below every layer)."""

from __future__ import annotations

import operator
import os

# Linux's largest pid (``/proc/sys/kernel/pid_max`` is at most 2**22): a pid read from shared
# memory or a record outside 1..PID_MAX was damaged or forged, and names no process
PID_MAX = 1 << 22


def valid_pid(pid: object) -> bool:
    """Whether ``pid`` could name one process (0 and negatives name groups to ``kill``)."""
    try:
        value = operator.index(pid)  # type: ignore[arg-type]
    except TypeError:
        return False
    return 0 < value <= PID_MAX


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists (another user's counts: it is alive, just not ours to signal).

    A value that cannot be a pid is not alive: it came from shared memory or a file that
    anyone of this user may write, and ``os.kill`` would act on a whole group (0, negatives)
    or raise (too large).
    """
    if not valid_pid(pid):
        return False
    try:
        os.kill(operator.index(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
