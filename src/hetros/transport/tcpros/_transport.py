"""The tcpros transport as the runtime sees it: every endpoint of a ``kind: ros1`` node.

Each such hetros node is one ROS 1 node (slave API, TCPROS server) registered with the plan's
master under ``/<node>``; its peers are whatever the master knows, not edges of the plan.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from ..._errors import UndeclaredEndpointError
from ..._log import get_logger
from ..._qos import DEFAULT_QOS, QoS
from ...plan import SERVICE_QOS, Plan, service_of
from .._base import Reader, Wake, Writer
from .._seam import Endpoint, Transport, TransportContext
from ._endpoints import Ros1ServiceCaller, Ros1ServiceServer, Ros1Writer, open_ros1_reader
from ._peer import Ros1Peer, Ros1Publication, get_ros1_parameter
from ._stream import SocketWaiter
from ._types import Ros1ServiceType, Ros1Type

log = get_logger("hetros.graph")


class Ros1Transport(Transport):
    kind = "tcpros"

    def __init__(self, context: TransportContext) -> None:
        super().__init__(context)
        if context.plan is None:
            raise AssertionError("ROS 1 nodes come from a plan")
        self._plan: Plan = context.plan
        self._lock = threading.Lock()
        self._peers: dict[str, Ros1Peer] = {}
        self._servers: dict[tuple[str, str], Ros1ServiceServer] = {}
        self._callers: dict[tuple[str, str], Ros1ServiceCaller] = {}
        self._waiters: dict[str, SocketWaiter] = {}
        # publications advertised before their node runs: (node, topic) -> it
        self._early: dict[tuple[str, str], Ros1Publication] = {}

    def wait_source(self, node: str) -> SocketWaiter | None:
        """A ROS 1 node's executor waits on its subscriptions' connections and in-process wake-ups."""
        if node not in self._plan.nodes or not self._plan.speaks_ros1(node):
            return None
        with self._lock:
            waiter = self._waiters.get(node)
            if waiter is None:
                waiter = self._waiters[node] = SocketWaiter()
            return waiter

    def _waiter(self, node: str) -> SocketWaiter:
        waiter = self.wait_source(node)
        assert waiter is not None
        return waiter

    def _peer(self, node: str) -> Ros1Peer:
        with self._lock:
            peer = self._peers.get(node)
            if peer is None:
                peer = Ros1Peer(node, self._plan.ros1_master, self._plan.ros1_host, self.context.stop)
                self._peers[node] = peer
            return peer

    def _declared(self, node: str, section: str, name: str) -> str:
        spec = self._plan.nodes[node]
        table: dict[str, str] = {"publish": spec.publish, "subscribe": spec.subscribe,
                                 "services": spec.services, "clients": spec.clients}[section]
        if name not in table:
            raise UndeclaredEndpointError(
                f"ROS 1 node {node!r} creates a {section} endpoint on {name!r} that the project file "
                f"does not declare: add it under nodes.{node}.{section}"
            )
        return table[name]

    def _qos(self, topic: str) -> QoS:
        return self._plan.ros1_qos.get(topic, DEFAULT_QOS)

    def _caller(self, node: str, service: str) -> Ros1ServiceCaller:
        typename = self._declared(node, "clients", service)
        with self._lock:
            caller = self._callers.get((node, service))
        if caller is None:
            caller = Ros1ServiceCaller(self._peer(node), service, Ros1ServiceType(self.context.types, typename),
                                       SERVICE_QOS)
            with self._lock:
                caller = self._callers.setdefault((node, service), caller)
        return caller

    def open_writer(self, endpoint: Endpoint) -> Writer:
        name, node = endpoint.name, endpoint.node
        if not endpoint.envelope:
            typename = self._declared(node, "publish", name)
            qos = self._qos(name)
            with self._lock:
                early = self._early.pop((node, name), None)
            if early is not None:
                return Ros1Writer(early)
            kind = Ros1Type(self.context.types, typename)
            return Ros1Writer(self._peer(node).advertise(name, kind, latch=qos.keeps_history, qos=qos))
        service, client = service_of(name)
        if client:
            server = self._servers.get((node, service))
            if server is None:
                raise UndeclaredEndpointError(f"ROS 1 node {node!r} replies on {service}, which it does not serve")
            return server.writer
        return self._caller(node, service).writer

    def open_reader(self, endpoint: Endpoint, wake: Wake) -> Reader:
        name, node = endpoint.name, endpoint.node
        if not endpoint.envelope:
            kind = Ros1Type(self.context.types, self._declared(node, "subscribe", name))
            return open_ros1_reader(self._peer(node), name, kind, self._qos(name), self._waiter(node), wake)
        service, client = service_of(name)
        if not client:
            kind_name = self._declared(node, "services", service)
            server = Ros1ServiceServer(self._peer(node), service, Ros1ServiceType(self.context.types, kind_name),
                                       SERVICE_QOS, wake, self.context.stop)
            self._servers[(node, service)] = server
            return server.reader
        return self._caller(node, service).attach(wake)

    def prepare(self, nodes: list[str]) -> None:
        """Advertise what ``nodes`` publish to the project's other ROS 1 nodes before they run, so those
        subscribers connect meanwhile (``wait_matched``): a ROS 1 publisher's first messages go to
        nobody otherwise, and a reliable topic must not lose them to start-up order."""
        for node in nodes:
            if not self._plan.speaks_ros1(node):
                continue
            for topic, typename in self._plan.nodes[node].publish.items():
                if self._planned_subscribers(topic):
                    qos = self._qos(topic)
                    publication = self._peer(node).advertise(topic, Ros1Type(self.context.types, typename),
                                                             latch=qos.keeps_history, qos=qos)
                    with self._lock:
                        self._early[(node, topic)] = publication

    def _planned_subscribers(self, topic: str) -> set[str]:
        """The project's ``kind: ros1`` nodes that subscribe to ``topic`` (they subscribe before they run; the
        ROS 1 bridge subscribes as it runs, and is not waited for)."""
        return {n for n, spec in self._plan.nodes.items() if topic in spec.subscribe and self._plan.speaks_ros1(n)}

    def wait_matched(self, timeout: float) -> list[str]:
        with self._lock:
            expected = {publication: len(self._planned_subscribers(topic))
                        for (_node, topic), publication in self._early.items()}
        deadline = time.monotonic() + timeout
        while not self.context.stop.is_set():
            short = {p.topic: (len(set(p.subscribers)), wanted) for p, wanted in expected.items()
                     if len(set(p.subscribers)) < wanted}
            if not short or time.monotonic() > deadline:
                for topic, (connected, wanted) in short.items():
                    log.warning("%s: %d of %d ROS 1 subscribers of the project connected after %g s; publishing "
                                "anyway", topic, connected, wanted, timeout)
                return list(short)
            time.sleep(0.01)
        return []

    def parameter(self, node: str, name: str) -> Any:
        """``/global``, ``relative`` (to ``/``) or ``~private`` (to ``/<node>``) on the master's server."""
        return get_ros1_parameter(self._plan.ros1_master, "/" + node, name)

    def close(self) -> None:
        with self._lock:
            callers, self._callers = list(self._callers.values()), {}
            peers, self._peers = list(self._peers.values()), {}
            waiters, self._waiters = list(self._waiters.values()), {}
            early, self._early = list(self._early.values()), {}
        for publication in early:
            publication.close()
        for caller in callers:
            caller.close()
        for peer in peers:
            peer.close()
        for waiter in waiters:
            waiter.close()
