"""Each node's own ``sys.argv``, though several nodes share a process.

A ROS node is a process of its own and parses its command line (``argparse``, ``rospy.myargv``, rclpy's
``remove_ros_args``). Under hetros several nodes may run as threads of one worker, whose command line is
the worker's (``_worker.py --plan ...``). ``sys.argv`` is therefore replaced, once per process, by a list
whose contents are the calling node thread's: ``[its script or module file, *args:]``; threads that are
no node (and any thread before a node sets its own) see the process' list.
"""

from __future__ import annotations

import sys
import threading
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from typing import Any, SupportsIndex, overload

_local = threading.local()


class NodeArgv(list[str]):
    """``sys.argv`` as the calling thread's node sees it; writes change that node's list only."""

    def _current(self) -> list[str]:
        mine: list[str] | None = getattr(_local, "argv", None)
        return mine if mine is not None else _process

    @overload
    def __getitem__(self, index: SupportsIndex) -> str: ...
    @overload
    def __getitem__(self, index: slice) -> list[str]: ...
    def __getitem__(self, index: SupportsIndex | slice) -> str | list[str]:
        return self._current()[index]

    def __setitem__(self, index: Any, value: Any) -> None:
        self._current()[index] = value

    def __delitem__(self, index: SupportsIndex | slice) -> None:
        del self._current()[index]

    def __len__(self) -> int:
        return len(self._current())

    def __iter__(self) -> Iterator[str]:
        return iter(list(self._current()))

    def __reversed__(self) -> Iterator[str]:
        return reversed(list(self._current()))

    def __contains__(self, value: object) -> bool:
        return value in self._current()

    def __eq__(self, other: object) -> bool:
        return self._current() == other

    __hash__ = None

    def __repr__(self) -> str:
        return repr(self._current())

    def __add__(self, other: Iterable[str]) -> list[str]:  # type: ignore[override]
        return [*self._current(), *other]

    def __radd__(self, other: Iterable[str]) -> list[str]:
        return [*other, *self._current()]

    def __iadd__(self, other: Iterable[str]) -> NodeArgv:  # type: ignore[override]
        self._current().extend(other)
        return self

    def append(self, value: str) -> None:
        self._current().append(value)

    def extend(self, values: Iterable[str]) -> None:
        self._current().extend(values)

    def insert(self, index: SupportsIndex, value: str) -> None:
        self._current().insert(index, value)

    def pop(self, index: SupportsIndex = -1) -> str:
        return self._current().pop(index)

    def remove(self, value: str) -> None:
        self._current().remove(value)

    def clear(self) -> None:
        self._current().clear()

    def index(self, value: str, *bounds: SupportsIndex) -> int:
        return self._current().index(value, *bounds)

    def count(self, value: str) -> int:
        return self._current().count(value)

    def copy(self) -> list[str]:
        return list(self._current())


_process: list[str] = list(sys.argv)


def set_node_argv(argv: list[str]) -> None:
    """Give the calling thread's node ``argv`` as its ``sys.argv`` (installed in ``sys`` on first use)."""
    global _process
    if not isinstance(sys.argv, NodeArgv):
        _process = list(sys.argv)
        sys.argv = NodeArgv(_process)
    _local.argv = list(argv)


@contextmanager
def node_argv(argv: list[str]) -> Iterator[None]:
    """``argv`` as the calling thread's ``sys.argv`` for a while: a node module imported now sees its node's
    command line (``def main(argv=sys.argv[1:])`` reads it at import), not the worker's."""
    previous: list[str] | None = getattr(_local, "argv", None)
    set_node_argv(argv)
    try:
        yield
    finally:
        _local.argv = previous
