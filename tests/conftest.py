from __future__ import annotations

import os
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture
def shm_session() -> str:
    return f"{os.getpid()}x{os.urandom(3).hex()}"
