"""Fixtures of the integration tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.support.ros1 import ros1_master


@pytest.fixture
def master() -> Iterator[tuple[str, dict[str, str]]]:
    """A `hetros master` on a free port: (its URI, the environment for ROS 1 processes)."""
    yield from ros1_master()
