"""Matched events: a publisher hears when a subscription to its topic comes or goes, and the other way;
both hear when the other's QoS cannot serve theirs (incompatible QoS).

ROS 2 raises these when discovery pairs two endpoints. hetros plans its graph before launch, so the
endpoints of other processes are known from the plan and matched from the start (their transports
connect before any node runs); what changes while a launch runs are the endpoints a node's code
creates and destroys, which this process sees directly. An endpoint's matched count is therefore the
planned endpoints of other processes plus the live ones of this process, and the events report the
changes of the second part, as ROS 2's would. Reports are coalesced until the node's executor runs
the callback (ROS 2 hands over the changes since the last report in the same way).

Where the project file gives a topic no QoS, each endpoint has the QoS its code asked for, and two of
this process' endpoints may not match (a best_effort offer to a reliable request): they are not
matched, each hears an incompatible-QoS event, and a subscription whose publishers here all fail it
hears nothing from them, as in ROS 2. (Where the project gives the QoS, every endpoint has it, and
``hetros check`` refused the project if endpoint requests disagreed.)
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

from .._qos import QoS, incompatible_policy

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


@dataclass(frozen=True)
class IncompatibleQosStatus:
    """As ROS 2's: endpoints found incompatible so far and since the last report, and the policy
    (``reliability``, ``durability``, ``deadline``, ``liveliness``, ``lease_duration``) that failed last."""

    total_count: int = 0
    total_count_change: int = 0
    last_policy_kind: str = ""


class MatchedWatch:
    """One endpoint's matches and mismatches, reported to its callbacks from the node's executor."""

    def __init__(self, node: Node, qos: QoS, on_matched: Callable[[MatchedStatus], object] | None,
                 on_incompatible_qos: Callable[[IncompatibleQosStatus], object] | None = None,
                 on_deaf: Callable[[bool], None] | None = None) -> None:
        self.node = node
        self.qos = qos  # what this endpoint offers or requests
        self.on_matched = on_matched
        self.on_incompatible_qos = on_incompatible_qos
        self.on_deaf = on_deaf  # a subscription told whether every publisher here fails its QoS
        self.peers: list[MatchedWatch] = []  # matched endpoints of this process
        self.clashes: list[MatchedWatch] = []  # incompatible endpoints of this process
        self._lock = threading.Lock()
        self.total = self.current = 0
        self._reported_total = self._reported_current = 0
        self.incompatible_total = 0
        self._reported_incompatible = 0
        self.last_policy = ""
        self._due = False

    def changed(self, delta: int) -> None:
        with self._lock:
            self.current += delta
            if delta > 0:
                self.total += delta
        self._schedule(self.on_matched is not None)

    def incompatible(self, policy: str) -> None:
        with self._lock:
            self.incompatible_total += 1
            self.last_policy = policy
        self._schedule(self.on_incompatible_qos is not None)

    def _schedule(self, wanted: bool) -> None:
        if self.on_deaf is not None:  # idempotent: a subscription changes its take only when deafness changes
            self.on_deaf(bool(self.clashes) and self.current == 0)
        with self._lock:
            if not wanted or self._due:
                return
            self._due = True
        self.node.executor.add_timer(time.monotonic(), self._report)

    def _report(self) -> None:
        with self._lock:
            self._due = False
            matched = MatchedStatus(self.total, self.total - self._reported_total,
                                    self.current, self.current - self._reported_current)
            incompatible = IncompatibleQosStatus(self.incompatible_total,
                                                 self.incompatible_total - self._reported_incompatible,
                                                 self.last_policy)
            self._reported_total, self._reported_current = self.total, self.current
            self._reported_incompatible = self.incompatible_total
        if incompatible.total_count_change and self.on_incompatible_qos is not None:
            self.on_incompatible_qos(incompatible)
        if (matched.total_count_change or matched.current_count_change) and self.on_matched is not None:
            self.on_matched(matched)


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
            present = list(self._live.get((topic, other), ()))
            self._live.setdefault((topic, role), []).append(watch)
            for peer in present:
                offered, requested = (watch, peer) if role == "publish" else (peer, watch)
                policy = incompatible_policy(offered.qos, requested.qos)
                if policy is None:
                    watch.peers.append(peer)
                    peer.peers.append(watch)
                else:
                    watch.clashes.append(peer)
                    peer.clashes.append(watch)
                    peer.incompatible(policy)
                    watch.incompatible(policy)
        count = self._elsewhere(topic, other) + len(watch.peers)
        if count:
            watch.changed(count)
        for peer in watch.peers:
            peer.changed(1)

    def left(self, topic: str, role: Role, watch: MatchedWatch) -> None:
        with self._lock:
            mine = self._live.get((topic, role), [])
            if watch not in mine:
                return
            mine.remove(watch)
            peers, watch.peers = watch.peers, []
            for peer in peers:
                peer.peers.remove(watch)
            for peer in watch.clashes:
                peer.clashes.remove(watch)
            clashed, watch.clashes = watch.clashes, []
        for peer in peers:
            peer.changed(-1)
        for peer in clashed:
            peer.changed(0)  # may no longer be deaf
