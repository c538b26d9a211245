"""Fixtures of the ROS 1 interop tests."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.support.ros1 import ros1_master


@pytest.fixture
def master() -> Iterator[tuple[str, dict[str, str]]]:
    """A `hetros master` on a free port: (its URI, the environment for ROS 1 processes)."""
    yield from ros1_master()


@pytest.fixture(params=["hetros", "rosmaster"])
def ros_master(request: pytest.FixtureRequest) -> Iterator[tuple[str, dict[str, str]]]:
    """Each master in turn: `hetros master`, then Debian's rosmaster (the interop tests hold for both)."""
    yield from ros1_master(request.param)
