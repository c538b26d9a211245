"""The ROS 1 bridge node: carries a project's exported and imported topics to and from ROS 1.

The planner adds it (``external: ros1:``) to the launcher's process as an ordinary node,
so inside the graph the lean transports stay: only this node speaks TCPROS. Exported
topics reach it like any subscription and go out once per ROS 1 subscriber; imported
ones come in on TCPROS and are published into the graph. Actions cross as actionlib's five
topics (``_ros1_actions``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..._errors import ShutdownError, TransportError
from ...msg import registry
from ...runtime import Node
from ...transport.tcpros import Ros1ActionType, Ros1NativeType, Ros1Peer, Ros1ServiceType, Ros1Type, ros1_store
from ..launcher._registry import session_folder
from ..observe._logs import LaunchLogs
from ._bridging import Imported
from ._ros1_actions import ExportedAction, ImportedAction


def bridge(node: Node) -> None:
    types = registry()
    peer = Ros1Peer(str(node.get_parameter("ros1_name")), str(node.get_parameter("master")),
                    str(node.get_parameter("host")))
    try:
        exports: dict[str, str] = node.get_parameter("export")
        imports: dict[str, str] = node.get_parameter("import")
        latched = set(node.get_parameter("latch", []))
        imported_here = Imported()
        for topic, typename in exports.items():
            outgoing = peer.advertise(topic, Ros1Type(types, typename), latch=topic in latched)
            node.create_subscription(types.get(typename), topic, imported_here.skip(outgoing.publish))
        for topic, typename in imports.items():
            publisher = node.create_publisher(types.get(typename), topic)
            peer.subscribe(topic, Ros1Type(types, typename), imported_here.keep(publisher.publish))
        export_services: dict[str, str] = node.get_parameter("export_services", {})
        import_services: dict[str, str] = node.get_parameter("import_services", {})
        for service, typename in export_services.items():
            client = node.create_client(types.get_service(typename), service)
            peer.advertise_service(service, Ros1ServiceType(types, typename), client.call)
        for service, typename in import_services.items():
            node.create_service(types.get_service(typename), service,
                                _forward(node, peer, service, Ros1ServiceType(types, typename)))
        export_actions: dict[str, str] = node.get_parameter("export_actions", {})
        import_actions: dict[str, str] = node.get_parameter("import_actions", {})
        for action, typename in export_actions.items():
            ExportedAction(node, peer, types.get_action(typename), action, Ros1ActionType(types, typename))
        for action, typename in import_actions.items():
            ImportedAction(node, peer, types.get_action(typename), action, Ros1ActionType(types, typename))
        exported = [*exports, *export_services, *export_actions]
        imported = [*imports, *import_services, *import_actions]
        node.log.info("ROS 1 bridge %s at %s: exports %s, imports %s", peer.name, peer.master_uri,
                      ", ".join(exported) or "nothing", ", ".join(imported) or "nothing")
        node.create_timer(0.2, _Rosout(node, peer).forward)
        node.spin()
    finally:
        peer.close()


# rosgraph_msgs/Log's levels by Python's level names
ROSOUT_LEVELS = {"DEBUG": 1, "INFO": 2, "WARNING": 4, "WARN": 4, "ERROR": 8, "CRITICAL": 16, "FATAL": 16}


class _Rosout:
    """The launch's log records (every process', from the session folder) published on ROS 1's /rosout,
    as rosgraph_msgs/Log: what rosout, rqt_console and `rostopic echo /rosout` read."""

    def __init__(self, node: Node, peer: Ros1Peer) -> None:
        self._kind = Ros1NativeType("rosgraph_msgs/msg/Log")
        self._publication = peer.advertise("/rosout", self._kind)
        self._logs = LaunchLogs(session_folder(node.graph.session))
        types = ros1_store().types
        self._header, self._time = types["std_msgs/msg/Header"], types["builtin_interfaces/msg/Time"]
        self._seq = 0

    def forward(self) -> None:
        for record in self._logs.new_records():
            self._seq += 1
            seconds = int(record.time)
            stamp = self._time(sec=seconds, nanosec=round((record.time - seconds) * 1e9) % 1_000_000_000)
            self._publication.publish(self._kind.cls(
                header=self._header(seq=self._seq, stamp=stamp, frame_id=""), level=ROSOUT_LEVELS.get(record.level, 2),
                name=f"/{record.name}", msg=record.message, file="", function="", line=0, topics=[]))


def _forward(node: Node, peer: Ros1Peer, service: str, kind: Ros1ServiceType) -> Callable[[Any], Any]:
    """A hetros service handler that calls the ROS 1 service of the same name. A call that fails as the
    launch stops (the ROS 1 side went first) ends the bridge quietly; any other failure is the node's."""

    def call(request: Any) -> Any:
        try:
            return peer.call_service(service, kind, request)
        except TransportError as exc:
            if node.graph.stop.wait(1.0):
                raise ShutdownError(f"ROS 1 service {service} failed as the launch stopped: {exc}") from exc
            raise

    return call
