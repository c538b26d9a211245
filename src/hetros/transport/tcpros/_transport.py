"""The tcpros transport as the runtime sees it: every endpoint of a ``kind: ros1`` node.

Each such hetros node is one ROS 1 node (slave API, TCPROS server) registered with the plan's
master under ``/<node>``; its peers are whatever the master knows, not edges of the plan.
"""

from __future__ import annotations

import threading
from typing import Any

from ..._errors import UndeclaredEndpointError
from ..._qos import DEFAULT_QOS, QoS
from ...plan import SERVICE_QOS, Plan, service_of
from .._base import Reader, Wake, Writer
from .._seam import Endpoint, Transport, TransportContext
from ._endpoints import Ros1ServiceCaller, Ros1ServiceServer, Ros1Writer, open_ros1_reader
from ._peer import Ros1Peer, get_ros1_parameter
from ._stream import SocketWaiter
from ._types import Ros1ServiceType, Ros1Type


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

    def parameter(self, node: str, name: str) -> Any:
        """``/global``, ``relative`` (to ``/``) or ``~private`` (to ``/<node>``) on the master's server."""
        return get_ros1_parameter(self._plan.ros1_master, "/" + node, name)

    def close(self) -> None:
        with self._lock:
            callers, self._callers = list(self._callers.values()), {}
            peers, self._peers = list(self._peers.values()), {}
            waiters, self._waiters = list(self._waiters.values()), {}
        for caller in callers:
            caller.close()
        for peer in peers:
            peer.close()
        for waiter in waiters:
            waiter.close()
