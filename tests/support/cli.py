"""The `hetros` command as a test runs it: in a folder of the test's own, whose launch registry (its
``XDG_RUNTIME_DIR``) no other test's launch shares."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path


def private_env(folder: Path) -> dict[str, str]:
    return dict(os.environ, XDG_RUNTIME_DIR=str(folder))


def hetros_in(*argv: str, cwd: Path, timeout: float = 90) -> subprocess.CompletedProcess[str]:
    """``hetros ARGV`` run in ``cwd`` (its launches registered there alone), output captured."""
    return subprocess.run([sys.executable, "-m", "hetros", *argv], capture_output=True, text=True, timeout=timeout,
                          check=False, cwd=cwd, env=private_env(cwd))


def looked_at(folder: Path, *argv: str) -> str:
    """What ``hetros ARGV`` prints once the launch run in ``folder`` is up (its registry entry appears a moment
    after it starts): retried for 30 s, then its failure asserted."""
    deadline = time.monotonic() + 30
    while True:
        done = hetros_in(*argv, cwd=folder)
        if done.returncode == 0 or time.monotonic() > deadline:
            assert done.returncode == 0, done.stdout + done.stderr
            return done.stdout
        time.sleep(0.3)
