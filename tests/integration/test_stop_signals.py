"""SIGINT and SIGTERM stop `hetros launch` from its first instant, also when inherited ignored
(`cmd &` in a script: from the first instant hetros's code runs), and an early stop is orderly: no ERROR
line, no traceback."""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "talker_listener" / "project.yaml"


def _until_caught(pid: int, signum: int) -> None:
    """Until process ``pid`` catches ``signum`` (``SigCgt`` in /proc): a signal inherited ignored and sent
    before the interpreter has run any of hetros's code is lost (or, SIGINT left to Python, a
    KeyboardInterrupt in its imports), whatever hetros does, and on a loaded machine Python takes more than
    the test's first 50 ms to start."""
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except FileNotFoundError:
            return
        caught = int(next(line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:")), 16)
        if caught >> (signum - 1) & 1:
            return
        time.sleep(0.002)


@pytest.mark.parametrize(("inherited", "signum"), [("ignored", signal.SIGINT), ("ignored", signal.SIGTERM),
                                                   ("default", signal.SIGINT)])
def test_an_early_stop_signal_is_honoured_and_quiet(inherited: str, signum: int) -> None:
    def start() -> None:
        if inherited == "ignored":
            signal.signal(signal.SIGINT, signal.SIG_IGN)
            signal.signal(signal.SIGTERM, signal.SIG_IGN)

    for after in (0.05, 0.5, 1.2, 2.2):
        began = time.monotonic()
        proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLE), "--duration", "20"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, preexec_fn=start)
        # SIGTERM, which Python itself leaves alone, is caught once hetros's handlers are in: a SIGINT before
        # that meets Python's own KeyboardInterrupt during the imports (seen on a loaded machine at 50 ms)
        _until_caught(proc.pid, signal.SIGTERM)
        time.sleep(max(0.0, after - (time.monotonic() - began)))
        proc.send_signal(signum)
        output, _ = proc.communicate(timeout=60)
        took = time.monotonic() - began
        assert took < after + 8, f"{signum!r} at {after} s was not honoured ({took:.1f} s):\n{output}"
        assert proc.returncode in (0, 128 + signum, 130), f"at {after} s: {proc.returncode}: {output}"
        assert "ERROR" not in output and "Traceback" not in output, output


def _signal_thread(pid: int, tid: int, signum: int) -> None:
    """``signum`` to one thread of ``pid``, as the kernel may deliver a signal sent to the process."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.tgkill(pid, tid, signum) != 0:
        raise OSError(ctypes.get_errno(), f"tgkill {pid} {tid}")


def _other_thread(pid: int) -> int:
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:
        others = [int(tid) for tid in os.listdir(f"/proc/{pid}/task") if int(tid) != pid]
        if others:
            return others[0]
        time.sleep(0.05)
    raise AssertionError(f"process {pid} started no thread")


@pytest.mark.parametrize(("command", "signum", "ready"), [
    (["master", "--port", "0"], signal.SIGTERM, "ROS master at"),
    (["launch", str(EXAMPLE)], signal.SIGINT, "I heard"),
])
def test_a_stop_signal_delivered_to_another_thread_still_stops_the_command(command: list[str], signum: int,
                                                                           ready: str) -> None:
    """The main thread waits for nothing but this signal; a handler only it can run must still run."""
    proc = subprocess.Popen([sys.executable, "-m", "hetros", *command], stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)
    try:
        assert proc.stdout is not None
        seen = []
        for line in proc.stdout:
            seen.append(line)
            if ready in line:
                break
        assert any(ready in line for line in seen), "".join(seen)
        _signal_thread(proc.pid, _other_thread(proc.pid), signum)
        output, _ = proc.communicate(timeout=15)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
            pytest.fail(f"{' '.join(command)} outlived {signum!r} sent to one of its other threads")
    assert proc.returncode in (0, 128 + signum, 130), proc.returncode
    assert "Traceback" not in output, output
