"""The ROS 1 bridge node: carries a project's exported and imported topics to and from ROS 1.

The planner adds it (``external: ros1:``) to the launcher's process as an ordinary node,
so inside the graph the lean transports stay: only this node speaks TCPROS. Exported
topics reach it like any subscription and go out once per ROS 1 subscriber; imported
ones come in on TCPROS and are published into the graph.
"""

from __future__ import annotations

from ..msg import registry
from ..runtime import Node
from ..transport.tcpros import Ros1Peer, Ros1Type


def bridge(node: Node) -> None:
    types = registry()
    peer = Ros1Peer(str(node.get_parameter("ros1_name")), str(node.get_parameter("master")),
                    str(node.get_parameter("host")))
    try:
        exports: dict[str, str] = node.get_parameter("export")
        imports: dict[str, str] = node.get_parameter("import")
        latched = set(node.get_parameter("latch", []))
        for topic, typename in exports.items():
            outgoing = peer.advertise(topic, Ros1Type(types, typename), latch=topic in latched)
            node.create_subscription(types.get(typename), topic, outgoing.publish)
        for topic, typename in imports.items():
            publisher = node.create_publisher(types.get(typename), topic)
            peer.subscribe(topic, Ros1Type(types, typename), publisher.publish)
        node.log.info("ROS 1 bridge %s at %s: exports %s, imports %s", peer.name, peer.master_uri,
                               ", ".join(exports) or "nothing", ", ".join(imports) or "nothing")
        node.spin()
    finally:
        peer.close()
