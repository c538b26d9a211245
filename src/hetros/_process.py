"""Processes of this machine, as hetros checks on them (below every layer)."""

from __future__ import annotations

import operator
import os
import signal

# Linux's largest pid (``/proc/sys/kernel/pid_max`` is at most 2**22): a pid read from shared
# memory or a record outside 1..PID_MAX was damaged or forged, and names no process
PID_MAX = 1 << 22


def valid_pid(pid: object) -> bool:
    """Whether ``pid`` could name one process (0 and negatives name groups to ``kill``; a JSON ``true``
    is no pid 1)."""
    if isinstance(pid, bool):
        return False
    try:
        value = operator.index(pid)  # type: ignore[arg-type]
    except TypeError:
        return False
    return 0 < value <= PID_MAX


def pid_alive(pid: int) -> bool:
    """Whether process ``pid`` exists (another user's counts: it is alive, just not ours to signal).

    A value that cannot be a pid is not alive: it came from shared memory or a file that
    anyone of this user may write, and ``os.kill`` would act on a whole group (0, negatives)
    or raise (too large). A zombie is not alive either: a worker whose launcher was killed
    has ended, but stays in the table until init reaps it (which some containers' init does
    late); its leftovers are a dead process's.
    """
    if not valid_pid(pid):
        return False
    try:
        os.kill(operator.index(pid), 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return not _zombie(pid)


def _zombie(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            state = stat.read(512).rpartition(b")")[2].split(maxsplit=1)[:1]
    except OSError:
        return False  # no /proc (or gone meanwhile): os.kill's word stands
    return state in ([b"Z"], [b"X"])


# what most often sends each signal to a hetros process, for the line that reports its death
_LIKELY = {
    "SIGBUS": "most often shared memory that ran out (a full /dev/shm: `df -h /dev/shm`) or a segment another "
              "process damaged",
    "SIGSEGV": "a crash in native code: a damaged shared-memory segment, or a C extension the node uses",
    "SIGKILL": "killed from outside: the kernel's out-of-memory killer (see `dmesg`) or a kill -9",
    "SIGABRT": "native code gave up (an assertion in a C extension or the simulator)",
    "SIGTERM": "stopped from outside (kill, a service manager)",
}


def death_cause(returncode: int) -> str:
    """How a child process ended, by its return code: the signal's name and its likely cause."""
    if returncode >= 0:
        return f"exit code {returncode}"
    try:
        name = signal.Signals(-returncode).name
    except ValueError:
        return f"killed by signal {-returncode}"
    likely = _LIKELY.get(name)
    return f"killed by {name}" + (f" ({likely})" if likely else "")
