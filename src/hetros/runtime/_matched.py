"""Matched events: a publisher hears when a subscription to its topic comes or goes, and the other way.

ROS 2 raises these when discovery pairs two endpoints. hetros plans its graph before launch, so the
endpoints of other processes are known from the plan and matched from the start (their transports
connect before any node runs); what changes while a launch runs are the endpoints a node's code
creates and destroys, which this process sees directly. An endpoint's matched count is therefore the
planned endpoints of other processes plus the live ones of this process, and the events report the
changes of the second part, as ROS 2's would. Reports are coalesced until the node's executor runs
the callback (ROS 2 hands over the changes since the last report in the same way).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    from ..plan import Plan
    from ._node import Node

Role = Literal["publish", "subscribe"]


@dataclass(frozen=True)
class MatchedStatus:
    """As ROS 2's: endpoints matched ever (``total``) and now (``current``), each with its change since
    the last report."""

    total_count: int = 0
    total_count_change: int = 0
    current_count: int = 0
    current_count_change: int = 0


class MatchedWatch:
    """One endpoint's matched count, reported to its callback from the node's executor."""

    def __init__(self, node: Node, callback: Callable[[MatchedStatus], object] | None) -> None:
        self.node = node
        self.callback = callback
        self._lock = threading.Lock()
        self.total = self.current = 0
        self._reported_total = self._reported_current = 0
        self._due = False

    def changed(self, delta: int) -> None:
        with self._lock:
            self.current += delta
            if delta > 0:
                self.total += delta
            if self.callback is None or self._due:
                return
            self._due = True
        self.node.executor.add_timer(time.monotonic(), self._report)

    def _report(self) -> None:
        with self._lock:
            self._due = False
            status = MatchedStatus(self.total, self.total - self._reported_total,
                                   self.current, self.current - self._reported_current)
            self._reported_total, self._reported_current = self.total, self.current
        if (status.total_count_change or status.current_count_change) and self.callback is not None:
            self.callback(status)


class Matches:
    """The live endpoints of this process per topic, and what the plan puts in other processes."""

    def __init__(self, plan: Plan | None, process: str) -> None:
        self._plan = plan
        self._process = process
        self._lock = threading.Lock()
        self._live: dict[tuple[str, Role], list[MatchedWatch]] = {}

    def _elsewhere(self, topic: str, role: Role) -> int:
        """The planned ``role`` endpoints of ``topic`` whose nodes run in another process (or hardware)."""
        channel = None if self._plan is None else self._plan.channels.get(topic)
        if channel is None or self._plan is None:
            return 0
        nodes = channel.publishers if role == "publish" else channel.subscribers
        plan = self._plan
        return sum(1 for node in nodes if node in plan.nodes and plan.process_of(node) != self._process)

    def joined(self, topic: str, role: Role, watch: MatchedWatch) -> None:
        other: Role = "subscribe" if role == "publish" else "publish"
        with self._lock:
            peers = list(self._live.get((topic, other), ()))
            self._live.setdefault((topic, role), []).append(watch)
        count = self._elsewhere(topic, other) + len(peers)
        if count:
            watch.changed(count)
        for peer in peers:
            peer.changed(1)

    def left(self, topic: str, role: Role, watch: MatchedWatch) -> None:
        other: Role = "subscribe" if role == "publish" else "publish"
        with self._lock:
            mine = self._live.get((topic, role), [])
            if watch not in mine:
                return
            mine.remove(watch)
            peers = list(self._live.get((topic, other), ()))
        for peer in peers:
            peer.changed(-1)

    def count(self, topic: str, role: Role) -> int:
        """How many ``role`` endpoints of ``topic`` there are now: planned elsewhere, live here."""
        with self._lock:
            here = len(self._live.get((topic, role), ()))
        return self._elsewhere(topic, role) + here
