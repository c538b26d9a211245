"""ROS 1's message definitions (rosbags' Noetic store): what the ROS 1 bridge, ``kind: ros1`` nodes and
hardware TCPROS map hetros's types onto."""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

_store: Typestore | None = None
_store_lock = threading.Lock()


def ros1_store() -> Typestore:
    """rosbags' ROS 1 (Noetic) definitions, loaded once per process."""
    global _store
    with _store_lock:
        if _store is None:
            from rosbags.typesys import Stores, get_types_from_msg, get_typestore

            _store = get_typestore(Stores.ROS1_NOETIC)
            _store.register({name: fields for text, name in ROS1_EXTRAS
                             for name, fields in get_types_from_msg(text, name).items()})
        return _store


# ROS 1 messages every robot's graph carries that rosbags' Noetic store lacks: (definition, name)
ROS1_EXTRAS = (("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"),)
