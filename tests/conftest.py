from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

from hetros.cli import CRASH_DIR_VARIABLE
from hetros.transport import SESSION_TAG_VARIABLE, cleanup_stale, new_session
from hetros.transport.shm._iceoryx import iceoryx_root
from hetros.transport.shm._sample import file_prefix
from hetros.transport.shm._stale import recorded_nodes

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
SHM = Path("/dev/shm")
# every session this suite starts (its launches inherit the variable) carries this tag, so the
# leak check looks at what the suite made and nothing else the machine runs
TAG = f"t{os.getpid():07d}"  # fixed width: no tag is the start of another
os.environ[SESSION_TAG_VARIABLE] = TAG
# where `hetros` writes the traceback of an exception it did not expect (a defect): any file there when
# the run ends fails it, whichever test's command hit it (the workers and their launches inherit this)
CRASHES = Path(os.environ.setdefault(CRASH_DIR_VARIABLE, f"/tmp/hetros-test-crashes-{TAG}"))


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
    cleanup_stale()  # what every launch does first: the nodes of processes the suite killed on purpose
    left = sorted(name for name in os.listdir(SHM) if name.startswith("hetros-") and _ours(name))
    # read by path, as the clean-up does: listing through iceoryx2 maps segments a test damaged on purpose
    root = iceoryx_root()
    for static_config in (root / "services").glob(f"{file_prefix()}*.service"):
        try:
            text = static_config.read_text(errors="replace")
        except FileNotFoundError:
            continue  # another launch of this account (a second suite beside this one) removed its service
        name = re.search(r'^service_name = "(.*)"$', text, re.MULTILINE)
        if name is not None and _ours(name.group(1)):
            left.append(f"iceoryx2 service {name.group(1)}")
    left += [f"iceoryx2 node {node.name}" for node in recorded_nodes(root) if _ours(node.name)]
    if left:
        print(f"\nshared memory left behind by the test run: {left}")
        session.exitstatus = pytest.ExitCode.TESTS_FAILED
    if not hasattr(session.config, "workerinput") and CRASHES.is_dir():
        reports = sorted(CRASHES.iterdir())
        if reports:
            print(f"\nhetros failed unexpectedly (a traceback where an error belongs) {len(reports)} time(s):")
            for report in reports[:5]:
                print(f"--- {report}\n{report.read_text(errors='replace')[-3000:]}")
            session.exitstatus = pytest.ExitCode.TESTS_FAILED
