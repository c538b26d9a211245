"""``hetros foxglove``: a running launch served to Foxglove over its WebSocket protocol.

Every topic this machine taps becomes a channel with its ROS 2 schema (``ros2msg``) and CDR
messages, so Foxglove's panels (images included) decode them as they would a ROS 2 bridge's.
A topic is tapped only while a Foxglove client subscribes to it, and at most ``max_rate``
messages a second: the cap is applied in the tap, before anything is encoded, so a live view
never slows a publisher. The server listens on 127.0.0.1 unless told otherwise.
"""

from __future__ import annotations

import threading
from typing import Any

from .._errors import InspectError
from .._log import get_logger
from ._bag import recordable
from ._inspect import RunningLaunch

log = get_logger("hetros.launch")
DEFAULT_PORT = 8765
DEFAULT_MAX_RATE = 30.0


class FoxgloveView:
    """The Foxglove server of one launch: channels for its topics, taps while clients look."""

    def __init__(self, launch: RunningLaunch, *, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 max_rate: float = DEFAULT_MAX_RATE) -> None:
        try:
            import foxglove
        except ImportError:
            raise InspectError("hetros foxglove needs the foxglove-sdk package: pip install 'hetros[live]' "
                               "(or .venv/bin/pip install foxglove-sdk)") from None
        self.launch = launch
        self.max_rate = max_rate
        self._context = foxglove.Context()
        self._channels: dict[str, Any] = {}
        for topic in recordable(launch, None):
            typename = launch.plan.channels[topic].type
            definition, _ = launch.types.store.generate_msgdef(typename, ros_version=2)
            schema = foxglove.Schema(name=typename, encoding="ros2msg", data=definition.encode())
            self._channels[topic] = foxglove.Channel(topic, message_encoding="cdr", schema=schema,
                                                     context=self._context)
        self._lock = threading.Lock()
        self._watchers: dict[str, int] = {}
        self._stops: dict[str, threading.Event] = {}
        view = self

        class Listener(foxglove.ServerListener):  # type: ignore[misc,name-defined]
            def on_subscribe(self, client: Any, channel: Any) -> None:
                view._watch(channel.topic, +1)

            def on_unsubscribe(self, client: Any, channel: Any) -> None:
                view._watch(channel.topic, -1)

        self.server = foxglove.start_server(name=f"hetros {launch.record.project} ({launch.record.session})",
                                            host=host, port=port, server_listener=Listener(),
                                            context=self._context)
        self.port = int(self.server.port)

    def _watch(self, topic: str, change: int) -> None:
        with self._lock:
            watchers = self._watchers.get(topic, 0) + change
            self._watchers[topic] = max(watchers, 0)
            if watchers > 0 and topic not in self._stops:
                stop = self._stops[topic] = threading.Event()
                threading.Thread(target=self._forward, args=(topic, stop), name=f"foxglove:{topic}",
                                 daemon=True).start()
            elif watchers <= 0 and topic in self._stops:
                self._stops.pop(topic).set()

    def _forward(self, topic: str, stop: threading.Event) -> None:
        channel = self._channels.get(topic)
        if channel is None:
            return
        try:
            for _topic, event in self.launch.tap_many([topic], data=True, max_rate=self.max_rate):
                if stop.is_set():
                    return
                if event is not None and event.data is not None:
                    channel.log(event.data, log_time=event.time_ns)
        except InspectError as exc:
            log.info("foxglove: %s", exc)

    def close(self) -> None:
        with self._lock:
            for stop in self._stops.values():
                stop.set()
            self._stops.clear()
        self.server.stop()
