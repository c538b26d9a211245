"""``ros_discovery_info``: how ROS 2 tools learn which nodes own which DDS endpoints.

DDS discovery alone shows readers and writers; ``ros2 node list`` and ``ros2 topic
info -v`` also need each participant's ``ParticipantEntitiesInfo`` (its gid, and per
node the gids of that node's readers and writers), published latched on this topic.
hetros lists each of its nodes whose endpoints reach ROS 2, under their own names.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import Any

import numpy as np

from ..._qos import QoS
from ...msg import TypeRegistry
from ._domain import DdsDomain, participant_gid
from ._endpoints import DdsTopicWriter
from ._names import DISCOVERY_TOPIC, DISCOVERY_TYPE

_LATCHED = QoS(reliability="reliable", history="keep_last", depth=1, durability="transient_local")


class DiscoveryInfo:
    """Keeps this participant's entry on ``ros_discovery_info`` current."""

    def __init__(self, domain: DdsDomain, types: TypeRegistry) -> None:
        self._domain = domain
        self._types = types
        self._nodes: dict[str, tuple[list[bytes], list[bytes]]] = {}
        self._lock = threading.Lock()
        self._writer = DdsTopicWriter.raw(domain, types, DISCOVERY_TOPIC, DISCOVERY_TYPE, _LATCHED)

    def add(self, node: str, readers: Sequence[Any] = (), writers: Sequence[Any] = ()) -> None:
        """Record DDS readers and writers as ``node``'s, and republish."""
        with self._lock:
            known_readers, known_writers = self._nodes.setdefault(node.lstrip("/"), ([], []))
            known_readers += [participant_gid(r) for r in readers]
            known_writers += [participant_gid(w) for w in writers]

    def publish(self) -> None:
        with self._lock:
            message = self.message()
        self._writer.write(message)

    def message(self) -> Any:
        get = self._types.get
        gid_type, node_type = get("rmw_dds_common/msg/Gid"), get("rmw_dds_common/msg/NodeEntitiesInfo")

        def gid(raw: bytes) -> Any:
            return gid_type(data=np.frombuffer(raw, dtype=np.uint8).copy())

        nodes = [node_type(node_namespace="/", node_name=name, reader_gid_seq=[gid(r) for r in readers],
                           writer_gid_seq=[gid(w) for w in writers])
                 for name, (readers, writers) in sorted(self._nodes.items())]
        return get(DISCOVERY_TYPE)(gid=gid(self._domain.gid), node_entities_info_seq=nodes)
