from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SHM = Path("/dev/shm")
# iceoryx2's machine-wide bookkeeping, created once and shared by every process
_SHARED = "node.0_10_0.global_mgmt"
_before: set[str] = set()


@pytest.fixture
def shm_session() -> str:
    return f"{os.getpid()}x{os.urandom(3).hex()}"


def pytest_sessionstart(session: pytest.Session) -> None:
    _before.update(os.listdir(SHM))


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """The suite must leave no shared memory behind: a leak fails the run."""
    left = sorted(name for name in set(os.listdir(SHM)) - _before if not name.endswith(_SHARED))
    if left:
        print(f"\nshared memory left behind by the test run: {left}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
