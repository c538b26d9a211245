"""Pids as read from shared memory and files: only real, running processes count as alive."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from hetros._process import PID_MAX, death_cause, pid_alive, valid_pid


@pytest.mark.parametrize("pid", [0, -1, -(1 << 40), PID_MAX + 1, 1 << 64, True, 3.0, "12"])
def test_values_that_cannot_be_pids_are_neither_valid_nor_alive(pid: object) -> None:
    assert not valid_pid(pid)
    assert not pid_alive(pid)  # type: ignore[arg-type]


def test_a_running_process_is_alive_and_a_zombie_is_not() -> None:
    """A worker whose launcher was killed ends as a zombie until init reaps it: its leftovers are a dead
    process's, and the next launch must clean them."""
    assert pid_alive(os.getpid())
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    deadline = time.monotonic() + 10
    while pid_alive(child.pid) and time.monotonic() < deadline:
        time.sleep(0.01)
    with open(f"/proc/{child.pid}/stat") as stat:  # not reaped yet: still in the table, as a zombie
        assert stat.read().rpartition(")")[2].split()[0] == "Z"
    assert not pid_alive(child.pid)
    child.wait()
    assert not pid_alive(child.pid)


def test_a_death_by_signal_is_named_with_its_likely_cause() -> None:
    text = death_cause(-signal.SIGBUS)
    assert "SIGBUS" in text and "/dev/shm" in text
