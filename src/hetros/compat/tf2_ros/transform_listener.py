"""tf2_ros.TransformListener: fills a Buffer from /tf and /tf_static.

ROS 2's (``TransformListener(buffer, node, spin_thread=True)``) and ROS 1's (``TransformListener(buffer)``,
on the rospy node) alike: with ``spin_thread`` (ROS 2's default, and always for rospy) a thread of the
listener takes the messages, so transforms arrive while the node's own thread waits in a lookup;
without it the node's executor runs the callback, as rclpy's would.

One transform tree per process: every listener in a process whose buffer keeps the same cache length
fills one tree, fed by the first of them; the buffers of the others look up in it."""

from __future__ import annotations

import threading
from typing import Any

from ..._errors import Error, TakeTimeoutError
from ..tf2_py import BufferCore
from ._endpoints import STATIC_QOS, STATIC_TOPIC, TF_QOS, TF_TOPIC, hetros_node, tf_type

_trees_lock = threading.Lock()
_trees: dict[int, tuple[BufferCore, list[TransformListener]]] = {}  # cache length -> (tree, its listeners)


class TransformListener:
    def __init__(self, buffer: Any, node: Any = None, *, spin_thread: bool = True, qos: Any = None,
                 static_qos: Any = None, static_only: bool = False, queue_size: Any = None,
                 buff_size: int = 65536, tcp_nodelay: bool = False) -> None:
        ros2 = node is not None and hasattr(node, "create_subscription")
        self.buffer = buffer
        self._node = hetros_node(node if ros2 else None)
        self._share_tree(buffer)
        message_type = tf_type()
        threaded = spin_thread or not ros2
        topics = [(STATIC_TOPIC, STATIC_QOS, self.static_callback)]
        if not static_only:
            topics.append((TF_TOPIC, TF_QOS, self.callback))
        self._subscriptions = [self._node.create_subscription(message_type, topic, None if threaded else callback,
                                                              qos=topic_qos)
                               for topic, topic_qos, callback in topics]
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        if threaded:
            for subscription, (topic, _qos, callback) in zip(self._subscriptions, topics, strict=True):
                thread = threading.Thread(target=self._take, args=(subscription, callback), daemon=True,
                                          name=f"tf listener {topic}")
                thread.start()
                self._threads.append(thread)

    def _share_tree(self, buffer: Any) -> None:
        key = buffer.cache_ns
        with _trees_lock:
            tree, listeners = _trees.setdefault(key, (buffer, []))
            listeners.append(self)
        if tree is not buffer:
            buffer.share_tree(tree)

    def _feeds(self) -> bool:
        with _trees_lock:
            _tree, listeners = _trees.get(self.buffer.cache_ns, (None, []))
            return bool(listeners) and listeners[0] is self

    def _take(self, subscription: Any, callback: Any) -> None:
        while not self._stop.is_set():
            try:
                message = subscription.take(timeout=0.2)
            except TakeTimeoutError:
                continue
            except Error:  # shutdown, or the subscription closed (unregister)
                return
            callback(message)

    def callback(self, data: Any) -> None:
        if self._feeds():
            for transform in data.transforms:
                self.buffer.set_transform(transform, "default_authority")

    def static_callback(self, data: Any) -> None:
        if self._feeds():
            for transform in data.transforms:
                self.buffer.set_transform_static(transform, "default_authority")

    def unregister(self) -> None:
        self._stop.set()
        for subscription in self._subscriptions:
            subscription.close()
        with _trees_lock:
            entry = _trees.get(self.buffer.cache_ns)
            if entry is not None and self in entry[1]:
                entry[1].remove(self)
                if not entry[1]:
                    del _trees[self.buffer.cache_ns]

    def __del__(self) -> None:
        self._stop.set()


__all__ = ["TransformListener"]
