"""``hetros foxglove``: a running launch served to Foxglove over its WebSocket protocol, in both of its
subprotocols (``foxglove.websocket.v1`` and the SDK's ``foxglove.sdk.v1``, see ``_foxglove_v1``), with client
publishing, the launch's services and its nodes' parameters.

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

import contextlib
import threading
from collections.abc import Callable
from typing import Any

from ..._errors import InspectError, LaunchError
from ..._log import get_logger
from ._bag import recordable
from ._foxglove_v1 import Channel, FrontServer
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
            import websockets  # noqa: F401  (the v1 side)
        except ImportError:
            raise InspectError("hetros foxglove needs the foxglove-sdk and websockets packages: pip install "
                               "'hetros[live]' (or .venv/bin/pip install foxglove-sdk websockets)") from None
        self.launch = launch
        self.max_rate = max_rate
        self._context = foxglove.Context()
        self._channels: dict[str, Any] = {}
        front_channels: list[Channel] = []
        for topic in recordable(launch, None):
            typename = launch.plan.channels[topic].type
            definition, _ = launch.types.store.generate_msgdef(typename, ros_version=2)
            schema = foxglove.Schema(name=typename, encoding="ros2msg", data=definition.encode())
            self._channels[topic] = foxglove.Channel(topic, message_encoding="cdr", schema=schema,
                                                     context=self._context)
            front_channels.append(Channel(len(front_channels) + 1, topic, typename, definition))
        self._lock = threading.Lock()
        self._watchers: dict[str, int] = {}
        self._stops: dict[str, threading.Event] = {}
        self._sinks: dict[str, list[Callable[[int, bytes], None]]] = {}
        self._advertised: dict[tuple[int, int], str] = {}  # (client, client channel) -> topic
        from foxglove.websocket import Capability

        self.server = foxglove.start_server(
            name=f"hetros {launch.record.project} ({launch.record.session})", host="127.0.0.1", port=0,
            server_listener=self._listener(foxglove), context=self._context, message_backlog_size=backlog,
            capabilities=[Capability.ClientPublish, Capability.Parameters, Capability.Services],
            supported_encodings=["cdr"], services=self._services(foxglove))
        self.front = FrontServer(name=f"hetros {launch.record.project} ({launch.record.session})", host=host,
                                 port=port, sdk_port=int(self.server.port), channels=front_channels,
                                 watch=self._sink, publish=self._client_published, backlog=backlog)
        self.port = self.front.port

    def _listener(self, foxglove: Any) -> Any:
        """What the SDK's server calls: subscriptions start and stop taps, client messages are published,
        parameters are the nodes' (``/node.name``)."""
        view = self

        class Listener(foxglove.ServerListener):  # type: ignore[misc]
            def on_subscribe(self, client: Any, channel: Any) -> None:
                view._watch(channel.topic, +1)

            def on_unsubscribe(self, client: Any, channel: Any) -> None:
                view._watch(channel.topic, -1)

            def on_client_advertise(self, client: Any, channel: Any) -> None:
                view._advertised[(client.id, channel.id)] = channel.topic

            def on_client_unadvertise(self, client: Any, client_channel_id: int) -> None:
                view._advertised.pop((client.id, client_channel_id), None)

            def on_message_data(self, client: Any, client_channel_id: int, data: bytes) -> None:
                topic = view._advertised.get((client.id, client_channel_id))
                if topic is not None:
                    with contextlib.suppress(InspectError):
                        view._client_published(topic, "", data)

            def on_get_parameters(self, client: Any, param_names: list[str], request_id: str | None = None) -> Any:
                return view._parameters(foxglove, param_names)

            def on_set_parameters(self, client: Any, parameters: list[Any], request_id: str | None = None) -> Any:
                for parameter in parameters:
                    node, _, name = parameter.name.lstrip("/").partition(".")
                    with contextlib.suppress(InspectError, LaunchError):
                        view.launch.set_parameter(node, name, parameter.get_value())
                return view._parameters(foxglove, [])

        return Listener()

    def _parameters(self, foxglove: Any, names: list[str]) -> list[Any]:
        found = []
        for node in sorted(self.launch.plan.nodes):
            if not self.launch.plan.runs_here(node) or self.launch.plan.in_hardware(node):
                continue
            with contextlib.suppress(InspectError, LaunchError):
                for name, value in sorted(self.launch.parameters(node).items()):
                    full = f"/{node}.{name}"
                    if (not names or full in names) and isinstance(value, bool | int | float | str | list):
                        found.append(foxglove.websocket.Parameter(full, value=value))
        return found

    def _services(self, foxglove: Any) -> list[Any]:
        """Every software service of the launch, callable from Foxglove's service panel (CDR both ways)."""
        from foxglove.websocket import MessageSchema, Service, ServiceSchema

        services = []
        for name in self.launch.services():
            with contextlib.suppress(InspectError):
                _, typename = self.launch.server_of(name)

                def schema(part: str, typename: str = typename) -> Any:
                    text, _ = self.launch.types.store.generate_msgdef(f"{typename}_{part}", ros_version=2)
                    return MessageSchema(encoding="cdr", schema=foxglove.Schema(
                        name=f"{typename}_{part}", encoding="ros2msg", data=text.encode()))

                def handle(request: Any, service: str = name, typename: str = typename) -> bytes:
                    answer = self.launch.call(service, self.launch.decode(f"{typename}_Request", request.payload))
                    return bytes(self.launch.codec(f"{typename}_Response").encode(answer))

                services.append(Service(name, schema=ServiceSchema(typename, request=schema("Request"),
                                                                   response=schema("Response")), handler=handle))
        return services

    def _client_published(self, topic: str, typename: str, data: bytes) -> None:
        """A message a Foxglove client published: into the launch, to every subscription of ``topic`` here."""
        self.launch.publish_bytes(topic, bytes(data))

    def _sink(self, topic: str, deliver: Callable[[int, bytes], None]) -> Callable[[], None]:
        """A v1 subscription: ``deliver`` gets each tapped message until the returned function is called."""
        with self._lock:
            self._sinks.setdefault(topic, []).append(deliver)
        self._watch(topic, +1)

        def stop() -> None:
            with self._lock:
                sinks = self._sinks.get(topic, [])
                if deliver in sinks:
                    sinks.remove(deliver)
            self._watch(topic, -1)
        return stop

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
                    for deliver in list(self._sinks.get(topic, ())):
                        deliver(event.time_ns, bytes(event.data))
        except InspectError as exc:
            log.info("foxglove: %s", exc)

    def close(self) -> None:
        with self._lock:
            for stop in self._stops.values():
                stop.set()
            self._stops.clear()
        self.front.close()
        self.server.stop()
