"""rclpy.service_introspection: the states a client or service may be put in.

ROS 2 publishes each call as an event on ``<service>/_service_event`` when a side is switched to
METADATA or CONTENTS. hetros plans every topic from the project file and publishes no such events,
so switching introspection on is refused, naming the service; OFF (every node's start) is kept.
"""

from __future__ import annotations

from enum import IntEnum
from typing import Any

from ..._errors import NodeError


class ServiceIntrospectionState(IntEnum):
    OFF = 0
    METADATA = 1
    CONTENTS = 2


def configure(service: str, state: Any) -> None:
    """What ``configure_introspection`` does on either side."""
    if ServiceIntrospectionState(int(state)) != ServiceIntrospectionState.OFF:
        raise NodeError(f"{service}: service introspection ({ServiceIntrospectionState(int(state)).name}) is not "
                        f"supported by hetros (it publishes no {service}/_service_event); keep it OFF, and watch the "
                        "service's calls with `hetros top` or `hetros node info`")


__all__ = ["ServiceIntrospectionState"]
