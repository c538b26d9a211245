"""SIGINT and SIGTERM stop `hetros launch` from its first instant, also when inherited ignored
(`cmd &` in a script), and an early stop is orderly: no ERROR line, no traceback."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "talker_listener" / "project.yaml"


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
        time.sleep(after)
        proc.send_signal(signum)
        output, _ = proc.communicate(timeout=60)
        took = time.monotonic() - began
        assert took < after + 8, f"{signum!r} at {after} s was not honoured ({took:.1f} s):\n{output}"
        assert proc.returncode in (0, 128 + signum, 130), f"at {after} s: {proc.returncode}: {output}"
        assert "ERROR" not in output and "Traceback" not in output, output
