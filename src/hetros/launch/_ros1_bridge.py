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

from ..msg import registry
from ..runtime import Node
from ..transport.tcpros import Ros1ActionType, Ros1Peer, Ros1ServiceType, Ros1Type
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
                                _forward(peer, service, Ros1ServiceType(types, typename)))
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
        node.spin()
    finally:
        peer.close()


def _forward(peer: Ros1Peer, service: str, kind: Ros1ServiceType) -> Callable[[Any], Any]:
    """A hetros service handler that calls the ROS 1 service of the same name."""

    def call(request: Any) -> Any:
        return peer.call_service(service, kind, request)

    return call
