"""The ROS 2 bridge node: carries what ``external: ros2:`` names to and from DDS.

The planner adds it to the launcher's process as an ordinary node, so inside the graph
the lean transports stay and only this node speaks DDS, with rmw_cyclonedds's names,
bytes and service headers: a stock ROS 2 node cannot tell it from another ROS 2 node.
Actions cross as their three services and two topics, as on ROS 2's own wire. Service
calls are forwarded without blocking the node (an action's ``get_result`` waits until
its goal ends), each answered when its reply arrives.
"""

from __future__ import annotations

import threading
import time
from concurrent.futures import Future
from typing import Any

from ..._errors import Error
from ...msg import TypeRegistry, registry
from ...plan import request_channel
from ...runtime import Client, Node, Replies
from ...transport import QoS
from ...transport.dds import (
    DdsDomain,
    DdsServiceClient,
    DdsServiceServer,
    DdsTopicReader,
    DdsTopicWriter,
    DiscoveryInfo,
)
from ..launcher._registry import session_folder
from ..observe._logs import LaunchLogs
from ._bridging import Imported

# how long a call from the graph waits for a ROS 2 server to be discovered before it is refused
_DISCOVERY_WAIT = 5.0


def bridge(node: Node) -> None:
    types = registry()
    p = node.get_parameter
    domain = DdsDomain(p("domain", None), interface=str(p("interface", "127.0.0.1")),
                       peers=list(p("peers", ["127.0.0.1"])), multicast=bool(p("multicast", False)))
    try:
        discovery = DiscoveryInfo(domain, types)
        owners: dict[str, dict[str, list[str]]] = p("owners", {})
        qos: dict[str, dict[str, Any]] = p("qos", {})
        imported_here = Imported()
        endpoints: list[Any] = []  # held for the bridge's lifetime: the binding deletes what nobody holds
        for topic, typename in dict(p("export", {})).items():
            writer = DdsTopicWriter(domain, types, topic, typename, QoS(**qos.get(topic, {})))
            endpoints.append(writer)
            node.create_subscription(types.get(typename), topic, imported_here.skip(_logged(node, writer.write)))
            for owner in owners["export"][topic]:
                discovery.add(owner, writers=[writer.writer])
        for topic, typename in dict(p("import", {})).items():
            publisher = node.create_publisher(types.get(typename), topic)
            reader = DdsTopicReader(domain, types, topic, typename, QoS(**qos.get(topic, {})),
                                    imported_here.keep(publisher.publish))
            endpoints.append(reader)
            for owner in owners["import"][topic]:
                discovery.add(owner, readers=[reader.reader])
        for service, typename in dict(p("export_services", {})).items():
            server = DdsServiceServer(domain, types, service, typename,
                                      _into_graph(node, node.create_client(types.get_service(typename), service)))
            endpoints.append(server)
            for owner in owners["export_services"][service]:
                discovery.add(owner, readers=[server.reader], writers=[server.writer])
        imported_services = []
        for service, typename in dict(p("import_services", {})).items():
            forwarded = _ImportedService(node, types, DdsServiceClient(domain, types, service, typename), typename,
                                          domain.domain_id)
            imported_services.append(forwarded)
            for owner in owners["import_services"][service]:
                discovery.add(owner, readers=[forwarded.dds.reader], writers=[forwarded.dds.writer])
        discovery.publish()
        exported = [*p("export", {}), *p("export_services", {})]
        imported = [*p("import", {}), *p("import_services", {})]
        node.log.info("ROS 2 bridge on DDS domain %d (%s): exports %s, imports %s", domain.domain_id,
                      domain.configured_by, ", ".join(exported) or "nothing", ", ".join(imported) or "nothing")
        rosout = _Rosout(node, DdsTopicWriter(domain, types, "/rosout", ROSOUT_TYPE, ROSOUT_QOS), types)
        endpoints.append(rosout.writer)
        node.create_timer(0.2, rosout.forward)
        if imported_services:
            def retry() -> None:
                for service in imported_services:
                    service.retry()

            node.create_timer(0.05, retry)
        node.spin()
    finally:
        domain.close()


# ROS 2's /rosout: every node's log records, kept for late joiners (rcl's QoS for it)
ROSOUT_TYPE = "rcl_interfaces/msg/Log"
ROSOUT_QOS = QoS(reliability="reliable", durability="transient_local", history="keep_last", depth=1000)
# rcl_interfaces/msg/Log's levels by Python's level names
ROSOUT_LEVELS = {"DEBUG": 10, "INFO": 20, "WARNING": 30, "WARN": 30, "ERROR": 40, "CRITICAL": 50, "FATAL": 50}


class _Rosout:
    """The launch's log records (every process', from the session folder) published on ROS 2's /rosout."""

    def __init__(self, node: Node, writer: DdsTopicWriter, types: TypeRegistry) -> None:
        self.node = node
        self.writer = writer
        self._logs = LaunchLogs(session_folder(node.graph.session))
        self._log = types.get(ROSOUT_TYPE)
        self._time = types.get("builtin_interfaces/msg/Time")

    def forward(self) -> None:
        for record in self._logs.new_records():
            seconds = int(record.time)
            self.writer.write(self._log(
                stamp=self._time(sec=seconds, nanosec=round((record.time - seconds) * 1e9) % 1_000_000_000),
                level=ROSOUT_LEVELS.get(record.level, 20), name=record.name, msg=record.message, file="",
                function="", line=0))


def _logged(node: Node, write: Any) -> Any:
    """Exported messages that DDS refuses are reported, never dropped silently."""

    def send(message: Any) -> None:
        try:
            write(message)
        except Error as exc:
            node.log.error("%s", exc)

    return send


def _into_graph(node: Node, client: Client) -> Any:
    """A ROS 2 request handed to the hetros server; its reply goes back when it arrives."""

    def handle(request: Any, respond: Any) -> None:
        def done(future: Future[Any]) -> None:
            try:
                respond(future.result())
            except Exception as exc:
                node.log.error("service %s: a ROS 2 call could not be answered: %s", client.name, exc)

        client.call_async(request).add_done_callback(done)

    return handle


class _ImportedService:
    """Serves a ROS 2 service inside the graph: each call is forwarded over DDS without blocking
    the node, and the reply written to the calling client when it arrives."""

    def __init__(self, node: Node, types: TypeRegistry, dds: DdsServiceClient, typename: str,
                 domain_id: int) -> None:
        self.node = node
        self.dds = dds
        self.domain_id = domain_id
        self.service = dds.service
        self._replies = Replies(node, self.service, f"{typename}_Response")
        self._waiting: list[tuple[float, int, str, Any]] = []
        self._lock = threading.Lock()
        node._check_declared_type(request_channel(self.service), f"{typename}_Request")
        self._requests = node.graph.open_reader(request_channel(self.service), node.name, f"{typename}_Request",
                                                lambda: node.executor.notify(self), envelope=True)
        node.executor.entities += 1

    def dispatch(self) -> bool:
        envelope = self._requests.try_take()
        if envelope is None:
            return False
        request_id, client, request = envelope
        self._forward(time.monotonic() + _DISCOVERY_WAIT, request_id, client, request)
        return True

    def pending(self) -> bool:
        return self._requests.pending()

    def retry(self) -> None:
        with self._lock:
            waiting, self._waiting = self._waiting, []
        for deadline, request_id, client, request in waiting:
            self._forward(deadline, request_id, client, request)

    def _forward(self, deadline: float, request_id: int, client: str, request: Any) -> None:
        if not self.dds.ready():
            if time.monotonic() < deadline:
                with self._lock:
                    self._waiting.append((deadline, request_id, client, request))
            else:
                self.node.log.error("service %s: no ROS 2 server was discovered within %g s; the call of %s "
                                    "is not answered (is the ROS 2 server running on domain %d?)",
                                    self.service, _DISCOVERY_WAIT, client, self.domain_id)
            return
        try:
            future = self.dds.call_async(request)
        except Error as exc:
            self.node.log.error("service %s: the call of %s could not be sent to ROS 2: %s", self.service, client, exc)
            return
        future.add_done_callback(lambda done: self._reply(request_id, client, done.result()))

    def _reply(self, request_id: int, client: str, response: Any) -> None:
        try:
            self._replies.send(request_id, client, response)
        except Error as exc:
            self.node.log.error("service %s: the ROS 2 reply to %s could not be delivered: %s",
                                self.service, client, exc)
