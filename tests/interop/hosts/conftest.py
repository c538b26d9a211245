"""Network namespaces shared by the multi-host tests (made once per module, torn down after)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from tests.support.netns import Namespace, namespaces


@pytest.fixture(scope="module")
def spaces() -> Iterator[list[Namespace]]:
    with namespaces(3) as made:
        yield made
