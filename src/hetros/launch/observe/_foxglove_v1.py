"""The port ``hetros foxglove`` listens on: Foxglove's older subprotocol, ``foxglove.websocket.v1`` (what
Foxglove Studio, Lichtblick, foxglove_bridge's clients and most tools speak), served here, and the SDK's
``foxglove.sdk.v1`` handed through to the SDK's server on a loopback port of its own.

The v1 side offers what the SDK side offers: every tapped topic as a channel (ROS 2 schema, CDR),
subscriptions fed by the same rate-capped taps, and client publishing into the launch. A client that does
not read holds one bounded queue of its own (``backlog`` messages, the oldest dropped): never a tap, never a
publisher.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import struct
import threading
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any, cast

from ..._errors import InspectError
from ..._log import get_logger
from ..._net import loopback_peer_uid

if TYPE_CHECKING:
    from websockets.typing import Subprotocol

log = get_logger("hetros.launch")

V1 = "foxglove.websocket.v1"
SDK_PREFIX = "foxglove.sdk."
_MESSAGE_DATA = 0x01  # server -> client: [op][subscription id u32][log time u64][payload]
_CLIENT_MESSAGE_DATA = 0x01  # client -> server: [op][client channel id u32][payload]
_WARNING, _ERROR = 1, 2


class Channel:
    """One topic as the v1 side advertises it."""

    def __init__(self, ident: int, topic: str, typename: str, schema: str) -> None:
        self.ident, self.topic, self.typename, self.schema = ident, topic, typename, schema

    def advertised(self) -> dict[str, Any]:
        return {"id": self.ident, "topic": self.topic, "encoding": "cdr", "schemaName": self.typename,
                "schema": self.schema, "schemaEncoding": "ros2msg"}


class FrontServer:
    """Both subprotocols on one port (see the module's docstring)."""

    def __init__(self, *, name: str, host: str, port: int, sdk_port: int, channels: list[Channel],
                 watch: Callable[[str, Callable[[int, bytes], None]], Callable[[], None]],
                 publish: Callable[[str, str, bytes], None], backlog: int) -> None:
        from websockets.sync.server import serve

        self.name, self.sdk_port, self.backlog = name, sdk_port, backlog
        self.channels = {channel.ident: channel for channel in channels}
        self._watch, self._publish = watch, publish
        offered = cast("list[Subprotocol]", [V1, "foxglove.sdk.v1"])
        self._server = serve(self._handle, host, port, subprotocols=offered, select_subprotocol=_select,
                             max_size=64 << 20)
        self.port = int(self._server.socket.getsockname()[1])
        self._thread = threading.Thread(target=self._server.serve_forever, name="foxglove-front", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._server.shutdown()
        self._thread.join(5)

    def _handle(self, connection: Any) -> None:
        peer = connection.remote_address
        if isinstance(peer, tuple) and len(peer) >= 2:
            uid = loopback_peer_uid((str(peer[0]), int(peer[1])), self.port)
            if uid is not None and uid != os.getuid():
                log.warning("foxglove: refused a client of user %d on the loopback port (it serves only you)", uid)
                connection.close(code=1008, reason="hetros foxglove serves only the account that started it")
                return
        chosen = connection.subprotocol or ""
        if chosen.startswith(SDK_PREFIX):
            self._hand_through(connection, chosen)
        else:
            _V1Session(self, connection).run()

    def _hand_through(self, connection: Any, subprotocol: str) -> None:
        """A ``foxglove.sdk.*`` client talks to the SDK's own server; frames pass unchanged both ways."""
        from websockets.sync.client import connect

        with connect(f"ws://127.0.0.1:{self.sdk_port}", subprotocols=cast("list[Subprotocol]", [subprotocol]),
                     max_size=64 << 20, open_timeout=10) as inner:
            def outward() -> None:
                with contextlib.suppress(Exception):
                    for frame in inner:
                        connection.send(frame)
                with contextlib.suppress(Exception):
                    connection.close()
            pump = threading.Thread(target=outward, name="foxglove-sdk-out", daemon=True)
            pump.start()
            with contextlib.suppress(Exception):
                for frame in connection:
                    inner.send(frame)
            with contextlib.suppress(Exception):
                inner.close()
            pump.join(5)


def _select(connection: Any, offered: Sequence[Subprotocol]) -> Subprotocol | None:
    """The client's first subprotocol of ours (any ``foxglove.sdk.*`` the SDK speaks)."""
    for protocol in offered:
        if protocol == V1 or protocol.startswith(SDK_PREFIX):
            return protocol
    return None


class _V1Session:
    """One ``foxglove.websocket.v1`` client: its subscriptions and the channels it advertised."""

    def __init__(self, front: FrontServer, connection: Any) -> None:
        self.front, self.connection = front, connection
        self.outbox: queue.Queue[str | bytes | None] = queue.Queue(maxsize=max(front.backlog, 1))
        self.unwatch: dict[int, Callable[[], None]] = {}
        self.advertised: dict[int, tuple[str, str]] = {}  # client channel id -> (topic, schema name)
        self.lock = threading.Lock()

    def run(self) -> None:
        writer = threading.Thread(target=self._write, name="foxglove-v1-out", daemon=True)
        writer.start()
        self._send_text({"op": "serverInfo", "name": self.front.name, "capabilities": ["clientPublish"],
                         "supportedEncodings": ["cdr"], "metadata": {}})
        self._send_text({"op": "advertise", "channels": [c.advertised() for c in self.front.channels.values()]})
        try:
            for frame in self.connection:
                if isinstance(frame, str):
                    self._on_text(frame)
                else:
                    self._on_binary(bytes(frame))
        except Exception as exc:
            log.info("foxglove: a v1 client went away (%s)", exc)
        finally:
            with self.lock:
                stops, self.unwatch = list(self.unwatch.values()), {}
            for stop in stops:
                stop()
            with contextlib.suppress(queue.Full):
                self.outbox.put_nowait(None)
            writer.join(5)

    # -- out: one writer thread; a full outbox drops its oldest frame ------------------------

    def _send_text(self, message: dict[str, Any]) -> None:
        self._queue(json.dumps(message))

    def _queue(self, frame: str | bytes) -> None:
        while True:
            try:
                self.outbox.put_nowait(frame)
                return
            except queue.Full:
                with contextlib.suppress(queue.Empty):
                    self.outbox.get_nowait()

    def _write(self) -> None:
        while (frame := self.outbox.get()) is not None:
            try:
                self.connection.send(frame)
            except Exception:
                return

    def _status(self, level: int, message: str) -> None:
        self._send_text({"op": "status", "level": level, "message": message})

    # -- in ------------------------------------------------------------------------------------

    def _on_text(self, text: str) -> None:
        try:
            request = json.loads(text)
            operation = request["op"]
        except (ValueError, KeyError, TypeError):
            self._status(_ERROR, f"not a foxglove.websocket.v1 request: {text[:80]!r}")
            return
        if operation == "subscribe":
            for item in request.get("subscriptions", []):
                self._subscribe(int(item["id"]), int(item["channelId"]))
        elif operation == "unsubscribe":
            for ident in request.get("subscriptionIds", []):
                with self.lock:
                    stop = self.unwatch.pop(int(ident), None)
                if stop is not None:
                    stop()
        elif operation == "clientAdvertise":
            self._client_advertise(request.get("channels", []))
        elif operation == "clientUnadvertise":
            for ident in request.get("channelIds", []):
                self.advertised.pop(int(ident), None)
        else:
            self._status(_WARNING, f"hetros does not serve {operation!r} (it serves subscribe, unsubscribe, "
                                   "clientAdvertise and clientUnadvertise)")

    def _subscribe(self, ident: int, channel_id: int) -> None:
        channel = self.front.channels.get(channel_id)
        if channel is None:
            self._status(_ERROR, f"subscription {ident}: no channel {channel_id}")
            return
        header = struct.Struct("<BIQ")

        def deliver(time_ns: int, data: bytes) -> None:
            self._queue(header.pack(_MESSAGE_DATA, ident, time_ns) + data)
        stop = self.front._watch(channel.topic, deliver)
        with self.lock:
            previous = self.unwatch.pop(ident, None)
            self.unwatch[ident] = stop
        if previous is not None:
            previous()

    def _client_advertise(self, channels: list[dict[str, Any]]) -> None:
        known = {c.topic: c for c in self.front.channels.values()}
        for entry in channels:
            topic, encoding, schema = entry.get("topic", ""), entry.get("encoding", ""), entry.get("schemaName", "")
            served = known.get(topic)
            if encoding != "cdr":
                self._status(_ERROR, f"client channel {topic}: encoding must be cdr, not {encoding!r}")
            elif served is None:
                self._status(_ERROR, f"client channel {topic}: the launch has no such topic (its topics: "
                                     f"{', '.join(sorted(known)) or 'none'})")
            elif schema and schema != served.typename:
                self._status(_ERROR, f"client channel {topic}: {topic} carries {served.typename}, not {schema}")
            else:
                self.advertised[int(entry["id"])] = (topic, served.typename)

    def _on_binary(self, frame: bytes) -> None:
        if len(frame) < 5 or frame[0] != _CLIENT_MESSAGE_DATA:
            self._status(_ERROR, f"binary frame of {len(frame)} bytes is not client message data")
            return
        ident = int.from_bytes(frame[1:5], "little")
        target = self.advertised.get(ident)
        if target is None:
            self._status(_ERROR, f"message on client channel {ident}, which was not advertised")
            return
        try:
            self.front._publish(target[0], target[1], frame[5:])
        except InspectError as exc:
            self._status(_ERROR, f"{target[0]}: {exc}")
