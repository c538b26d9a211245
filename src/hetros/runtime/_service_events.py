"""A service's calls as events, ROS 2's service introspection: what `hetros service echo` shows.

ROS 2 publishes a ``<srv>_Event`` on ``<service>/_service_event`` at four moments of a call
(the client sent the request, the server received it, the server sent its response, the client
received it). hetros makes those events at the same four moments, but only while someone looks:
they go to the tap of ``<service>/_service_event`` in the process, never onto a transport, so a
service nobody echoes pays one attribute test per call.

``configure_introspection`` decides, per side, what is shown: OFF nothing, METADATA the event
without request or response, CONTENTS everything. A side that was never configured shows
CONTENTS: looking is something the graph's owner asks for from the command line, on a launch
only they can reach.
"""

from __future__ import annotations

import enum
import itertools
import time
from typing import TYPE_CHECKING, Any

from ..msg import ServiceType

if TYPE_CHECKING:
    from ._node import Node

EVENT_TOPIC_SUFFIX = "/_service_event"


class Introspection(enum.IntEnum):
    OFF = 0
    METADATA = 1
    CONTENTS = 2


class EventKind(enum.IntEnum):
    """service_msgs/msg/ServiceEventInfo's event types."""

    REQUEST_SENT = 0
    REQUEST_RECEIVED = 1
    RESPONSE_SENT = 2
    RESPONSE_RECEIVED = 3


def client_gid(node: str) -> bytes:
    """A client's 16-byte id in its events: stable for the node, as a DDS writer's GUID is for its run."""
    import hashlib  # here, not above: moving messages must not load OpenSSL

    return hashlib.blake2b(node.encode(), digest_size=16).digest()


class ServiceEvents:
    """One side (a server or a client) of one service, as events for the process' tap."""

    def __init__(self, node: Node, service: str, srv_type: ServiceType) -> None:
        self.state = Introspection.CONTENTS
        self._point = node.graph.tap_point(service + EVENT_TOPIC_SUFFIX, f"{srv_type.name}_Event")
        self._types = node.graph.types
        self._event: Any = None
        self._sequence = itertools.count(1)

    def next_sequence(self) -> int:
        """A sequence number for a call that came with none (one made from the command line)."""
        return next(self._sequence)

    def offer(self, kind: EventKind, sequence: int, client: str, message: Any) -> None:
        point = self._point
        if not point.sinks or self.state == Introspection.OFF:
            return
        if self._event is None:
            self._event = self._types.get(point.typename)
            self._info = self._types.get("service_msgs/msg/ServiceEventInfo")
            self._time = self._types.get("builtin_interfaces/msg/Time")
        now = time.time_ns()
        info = self._info(event_type=int(kind), stamp=self._time(sec=now // 1_000_000_000, nanosec=now % 1_000_000_000),
                          client_gid=list(client_gid(client)), sequence_number=sequence)
        contents = [message] if self.state == Introspection.CONTENTS else []
        is_request = kind in (EventKind.REQUEST_SENT, EventKind.REQUEST_RECEIVED)
        event = self._event(info=info, request=contents if is_request else [],
                            response=[] if is_request else contents)
        point.published += 1
        point.offer(event)
