"""ROS 2's names on DDS, as rmw_cyclonedds spells them.

A stock ROS 2 peer finds a topic only when both the DDS topic name and the DDS type
name are exactly these; a wrong one fails silently (the endpoints never match), so
they are made in this one place and tested against hand-written expectations.
"""

from __future__ import annotations

from ..._errors import TransportError

# ROS 2's prefixes: topics, service requests, service replies
TOPIC_PREFIX = "rt"
REQUEST_PREFIX = "rq"
REPLY_PREFIX = "rr"
DISCOVERY_TOPIC = "ros_discovery_info"
DISCOVERY_TYPE = "rmw_dds_common/msg/ParticipantEntitiesInfo"


def _relative(name: str) -> str:
    if not name.startswith("/") or name.endswith("/") or "//" in name:
        raise TransportError(f"a ROS 2 name must be absolute like '/chatter', not {name!r}")
    return name[1:]


def topic_name(topic: str) -> str:
    """``/chatter`` → ``rt/chatter``."""
    return f"{TOPIC_PREFIX}/{_relative(topic)}"


def request_topic(service: str) -> str:
    """``/add_two_ints`` → ``rq/add_two_intsRequest``."""
    return f"{REQUEST_PREFIX}/{_relative(service)}Request"


def reply_topic(service: str) -> str:
    """``/add_two_ints`` → ``rr/add_two_intsReply``."""
    return f"{REPLY_PREFIX}/{_relative(service)}Reply"


def dds_type_name(typename: str) -> str:
    """``std_msgs/msg/String`` → ``std_msgs::msg::dds_::String_``; services' halves and an
    action's derived types keep their interface kind (``…::srv::dds_::AddTwoInts_Request_``)."""
    parts = typename.split("/")
    if len(parts) != 3 or not all(parts):
        raise TransportError(f"a ROS 2 type name must be 'package/kind/Name', not {typename!r}")
    package, kind, name = parts
    return f"{package}::{kind}::dds_::{name}_"
