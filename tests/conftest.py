from __future__ import annotations

import os
from pathlib import Path

import pytest

from hetros.transport import SESSION_TAG_VARIABLE, new_session
from hetros.transport.shm._iceoryx import iox2

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SHM = Path("/dev/shm")
# every session this suite starts (its launches inherit the variable) carries this tag, so the
# leak check looks at what the suite made and nothing else the machine runs
TAG = f"t{os.getpid():07d}"  # fixed width: no tag is the start of another
os.environ[SESSION_TAG_VARIABLE] = TAG


@pytest.fixture
def shm_session() -> str:
    return new_session()


def _ours(name: str) -> bool:
    return f"x{TAG}" in name


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """The suite must leave no shared memory behind: a leak fails the run.

    Only what this suite made counts: its credits files, and the iceoryx2 services and nodes
    whose names carry its sessions (another launch on the machine may hold shared memory).
    """
    left = sorted(name for name in os.listdir(SHM) if name.startswith("hetros-") and _ours(name))
    try:
        config = iox2.config.global_config()
        names = [s.name().to_string() for s in iox2.Service.list(config, iox2.ServiceType.Ipc)]
        left += sorted(f"iceoryx2 service {name}" for name in names if _ours(name))
        for state in iox2.Node.list(iox2.ServiceType.Ipc, config):
            details = state._0.details
            if details is not None and _ours(details.name.as_str()):
                left.append(f"iceoryx2 node {details.name.as_str()} ({type(state).__name__})")
    except Exception as exc:  # iceoryx2 raises its own exception classes
        print(f"\nthe iceoryx2 services and nodes could not be listed: {type(exc).__name__}: {exc}")
    if left:
        print(f"\nshared memory left behind by the test run: {left}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
