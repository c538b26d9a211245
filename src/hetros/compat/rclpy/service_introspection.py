"""rclpy.service_introspection: the states a client or service may be put in.

ROS 2 publishes each call as an event on ``<service>/_service_event`` when a side is switched to
METADATA or CONTENTS. hetros makes the same events for `hetros service echo` (while it looks,
never onto a transport); the state set here decides what a side shows: OFF nothing, METADATA
the events without request or response, CONTENTS everything (a side never configured shows
CONTENTS).
"""

from __future__ import annotations

from enum import IntEnum
from typing import Any

from ..._errors import NodeError
from ...runtime import Introspection


class ServiceIntrospectionState(IntEnum):
    OFF = 0
    METADATA = 1
    CONTENTS = 2


def configure(side: Any, service: str, state: Any) -> None:
    """What ``configure_introspection`` does on either side (``side``: hetros's client or server)."""
    try:
        side.events.state = Introspection(int(state))
    except (TypeError, ValueError):
        raise NodeError(f"{service}: introspection_state must be one of ServiceIntrospectionState's (OFF, "
                        f"METADATA, CONTENTS), not {state!r}") from None


__all__ = ["ServiceIntrospectionState"]
