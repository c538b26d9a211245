"""``hetros foxglove``: a running launch served to Foxglove over its WebSocket protocol.

Every topic this machine taps becomes a channel with its ROS 2 schema (``ros2msg``) and CDR
messages, so Foxglove's panels (images included) decode them as they would a ROS 2 bridge's.
A topic is tapped only while a Foxglove client subscribes to it, and at most ``max_rate``
messages a second: the cap is applied in the tap, before anything is encoded, so a live view
never slows a publisher.

Foxglove's protocol has no authentication: every account of the machine that reaches the
port sees every topic. The server listens on 127.0.0.1; any other interface is refused unless
the project file lists it (``foxglove_hosts``). Each client has a bounded backlog (``backlog``
messages; the oldest is dropped when a client does not read), and a topic's tap outlives its
last subscriber by ``TAP_LINGER`` seconds, so a flood of subscribes costs the publisher one
attach, not one per request.
"""

from __future__ import annotations

import threading
from typing import Any

from ..._errors import InspectError
from ..._log import get_logger
from ._bag import recordable
from ._inspect import RunningLaunch

log = get_logger("hetros.launch")
DEFAULT_PORT = 8765
DEFAULT_MAX_RATE = 30.0
# messages buffered per client (the SDK's default, 1024, held 1.4 GB for five clients that never read)
DEFAULT_BACKLOG = 8
TAP_LINGER = 2.0
_LOOPBACK = {"127.0.0.1", "localhost", "::1"}


def check_host(host: str, allowed: tuple[str, ...]) -> str:
    """The interface to listen on: loopback, or one the project file allows."""
    if host not in _LOOPBACK and host not in allowed:
        raise InspectError(f"--host {host}: hetros foxglove serves every topic without authentication, so it listens "
                           "on 127.0.0.1 only, unless the project file lists the interface (foxglove_hosts: "
                           f"[{host}]); or reach it through an SSH tunnel")
    return host


class FoxgloveView:
    """The Foxglove server of one launch: channels for its topics, taps while clients look."""

    def __init__(self, launch: RunningLaunch, *, host: str = "127.0.0.1", port: int = DEFAULT_PORT,
                 max_rate: float = DEFAULT_MAX_RATE, backlog: int = DEFAULT_BACKLOG) -> None:
        check_host(host, launch.plan.foxglove_hosts)
        if not 1 <= backlog <= 1024:
            raise InspectError(f"backlog must be 1..1024 messages per client, not {backlog!r}")
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
                                            context=self._context, message_backlog_size=backlog)
        self.port = int(self.server.port)

    def _watch(self, topic: str, change: int) -> None:
        with self._lock:
            if topic not in self._channels:
                return
            watchers = max(self._watchers.get(topic, 0) + change, 0)
            self._watchers[topic] = watchers
            if watchers > 0 and topic not in self._stops:
                stop = self._stops[topic] = threading.Event()
                threading.Thread(target=self._forward, args=(topic, stop), name=f"foxglove:{topic}",
                                 daemon=True).start()
            elif watchers == 0 and topic in self._stops:
                timer = threading.Timer(TAP_LINGER, self._stop_if_unwatched, args=(topic,))
                timer.daemon = True
                timer.start()

    def _stop_if_unwatched(self, topic: str) -> None:
        with self._lock:
            if self._watchers.get(topic, 0) == 0 and topic in self._stops:
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
