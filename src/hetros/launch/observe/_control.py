"""Each process of a launch answers looks from outside on a Unix socket only its user can reach.

The socket is ``<session folder>/<process>.sock`` in the private launch registry
(``_registry.session_folder``: mode 0700, so another user cannot even reach it) and every
connection's peer is checked again (``SO_PEERCRED``). What crosses it is JSON and raw CDR
message bytes, never pickle.

A frame is an 8-byte header (JSON length, payload length, little endian), the JSON object,
then the payload. A request is one frame; most answers are one frame; a tap answers with a
frame per message until the looker hangs up.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..._errors import InspectError
from ..._log import get_logger
from ...runtime import ProjectParameters, TapSink, check_rate
from ...transport import MessageCodec

if TYPE_CHECKING:
    from ...msg import ServiceType
    from ...runtime import Host, Node

log = get_logger("hetros.launch")
_FRAME = struct.Struct("<II")
MAX_HEADER = 1 << 20
# a message published or a request made from the command line: a 4K camera frame is 25 MB
MAX_PAYLOAD = 256 << 20
# looks served at once by one process (each holds a thread); more are answered "busy" and closed
MAX_CONNECTIONS = 32
# a look must send its request this soon after connecting, and read what it is sent this soon: a
# connection that does neither holds no thread for long
REQUEST_SECONDS = 10.0
SEND_SECONDS = 60.0
_SO_PEERCRED = struct.Struct("3i")


def send_frame(sock: socket.socket, header: dict[str, Any], payload: bytes | bytearray | memoryview = b"") -> None:
    text = json.dumps(header).encode()
    sock.sendall(_FRAME.pack(len(text), len(payload)) + text)
    if payload:
        sock.sendall(payload)


def _receive_exactly(sock: socket.socket, size: int) -> bytes:
    """``size`` bytes, read into one buffer (no second copy of a large payload)."""
    buffer = bytearray(size)
    view = memoryview(buffer)
    got = 0
    while got < size:
        count = sock.recv_into(view[got:], min(size - got, 1 << 20))
        if not count:
            raise InspectError(f"the other end closed the connection {got} bytes into a {size}-byte read")
        got += count
    return bytes(buffer) if size < 4096 else buffer  # type: ignore[return-value]  # a bytearray reads as bytes


def receive_frame(sock: socket.socket) -> tuple[dict[str, Any], bytes]:
    """The next frame; a frame that breaks the format raises InspectError naming the offset and the fault."""
    header_size, payload_size = _FRAME.unpack(_receive_exactly(sock, _FRAME.size))
    if header_size > MAX_HEADER or payload_size > MAX_PAYLOAD:
        raise InspectError(f"control frame claims a {header_size}-byte header and a {payload_size}-byte payload "
                           f"(at most {MAX_HEADER} and {MAX_PAYLOAD}): not a hetros control peer")
    raw = _receive_exactly(sock, header_size)
    try:
        header = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InspectError(f"control frame header at offset {_FRAME.size} is not JSON: {exc}") from None
    if not isinstance(header, dict):
        raise InspectError(f"control frame header must be a JSON object, not {type(header).__name__}")
    return header, _receive_exactly(sock, payload_size) if payload_size else b""


@contextlib.contextmanager
def short_path(path: Path) -> Iterator[str]:
    """``path`` as a name short enough for a Unix socket (108 bytes at most): through an open
    descriptor of its folder, so a deep ``$XDG_RUNTIME_DIR`` or temporary folder works too."""
    folder = os.open(path.parent, os.O_RDONLY | os.O_DIRECTORY)
    try:
        yield f"/proc/self/fd/{folder}/{path.name}"
    finally:
        os.close(folder)


def peer_uid(sock: socket.socket) -> int:
    _pid, uid, _gid = _SO_PEERCRED.unpack(sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, _SO_PEERCRED.size))
    return int(uid)


def _thread_cpu_seconds(native_id: int | None) -> float:
    """CPU time (user + system) of one thread of this process, from /proc."""
    if native_id is None:
        return 0.0
    try:
        fields = Path(f"/proc/self/task/{native_id}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _resident_bytes() -> int:
    try:
        return int(Path("/proc/self/statm").read_text().split()[1]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, IndexError, ValueError):
        return 0


class ControlServer:
    """The look-in socket of one process of a launch."""

    def __init__(self, host: Host, folder: Path, process: str) -> None:
        self.host = host
        self.graph = host.graph
        self.process = process
        self.path = folder / f"{process}.sock"
        self.path.unlink(missing_ok=True)
        self._listener = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        previous = os.umask(0o177)
        try:
            with short_path(self.path) as name:
                self._listener.bind(name)
        finally:
            os.umask(previous)
        self._listener.listen(16)
        self._closed = False
        self._serving = threading.BoundedSemaphore(MAX_CONNECTIONS)
        self._codecs: dict[str, MessageCodec] = {}
        self._thread = threading.Thread(target=self._accept, name=f"control:{process}", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._closed = True
        with contextlib.suppress(OSError):
            self._listener.shutdown(socket.SHUT_RDWR)
        self._listener.close()
        self.path.unlink(missing_ok=True)

    def _accept(self) -> None:
        while not self._closed:
            try:
                connection, _ = self._listener.accept()
            except OSError:
                return
            if peer_uid(connection) != os.getuid():
                connection.close()  # the folder's mode already keeps others out; this keeps out a moved socket
                continue
            if not self._serving.acquire(blocking=False):
                with connection, contextlib.suppress(OSError):
                    connection.settimeout(1.0)
                    send_frame(connection, {"error": f"{self.process} serves {MAX_CONNECTIONS} looks at once "
                                                     "already; end one, or try again"})
                continue
            threading.Thread(target=self._serve, args=(connection,), name=f"control:{self.process}:peer",
                             daemon=True).start()

    def _serve(self, connection: socket.socket) -> None:
        try:
            self._serve_one(connection)
        finally:
            self._serving.release()

    def _serve_one(self, connection: socket.socket) -> None:
        with connection:
            try:
                connection.settimeout(REQUEST_SECONDS)
                request, payload = receive_frame(connection)
                connection.settimeout(SEND_SECONDS)
            except (OSError, InspectError):
                return  # the looker hung up, sent nothing in time, or sent something that is not a control frame
            try:
                operation = request.get("op")
                handler = getattr(self, f"_op_{operation}", None) if isinstance(operation, str) else None
                if handler is None:
                    send_frame(connection, {"error": f"unknown request {operation!r}"})
                    return
                handler(connection, request, payload)
            except OSError:
                return  # the looker hung up
            except Exception as exc:  # a look must never take the graph down: report it to the looker
                log.warning("a request from hetros' command line failed in %s: %s: %s", self.process,
                            type(exc).__name__, exc)
                with contextlib.suppress(OSError):
                    send_frame(connection, {"error": f"{type(exc).__name__}: {exc}"})

    def _codec(self, typename: str) -> MessageCodec:
        codec = self._codecs.get(typename)
        if codec is None:
            codec = self._codecs[typename] = MessageCodec(self.graph.types, typename)
        return codec

    # -- requests ----------------------------------------------------------------------------

    def _op_stats(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        nodes = {}
        for thread in self.host.threads:
            live = self.graph.nodes.get(thread.spec.name)
            handling = {}
            if live is not None:
                for name, stats in live.handling_stats().items():
                    handling[name] = stats.snapshot()
            figures = live.figures() if live is not None and live.figures is not None else {}
            triggers = [[cause, topic, count] for (cause, topic), count in live.triggers.items()] \
                if live is not None else []
            nodes[thread.spec.name] = {"cpu_s": _thread_cpu_seconds(thread.thread.native_id),
                                       "alive": thread.thread.is_alive(), "handling": handling, "figures": figures,
                                       "triggers": triggers}
        topics: dict[str, dict[str, Any]] = {
            topic: {"published": point.published, "type": point.typename, "dropped": 0, "stalls": 0, "bytes": 0}
            for topic, point in self.graph.taps().items()}
        for live in list(self.graph.nodes.values()):
            for entity in live.entities():
                topic_name = getattr(entity, "topic", None)
                if topic_name is None or not hasattr(entity, "counters"):
                    continue
                entry = topics.setdefault(topic_name, {"published": 0, "type": entity.typename, "dropped": 0,
                                                       "stalls": 0, "bytes": 0})
                for counter, value in entity.counters().items():
                    if counter in entry:
                        entry[counter] += value
        send_frame(connection, {"process": self.process, "pid": os.getpid(), "time": time.time(),
                                "cpu_s": sum(os.times()[:2]), "rss": _resident_bytes(), "nodes": nodes,
                                "topics": topics})

    def _op_nodes(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        """The full ROS names of the nodes alive here: the plan's, and those their code made beside them."""
        names = sorted({name for live in list(self.graph.nodes.values()) for name in live.ros_nodes()})
        send_frame(connection, {"process": self.process, "nodes": names})

    def _op_tap(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        topic = _text(request, "topic")
        points = self.graph.taps()
        point = points.get(topic)
        if point is None:
            send_frame(connection, {"error": f"{topic} has no publisher running in {self.process} yet"})
            return
        codec = self._codec(point.typename)
        wants_data = bool(request.get("data", True))
        sink = TapSink(codec, data=wants_data, max_rate=check_rate(request.get("max_rate", 0), "max_rate"))
        point.attach(sink)
        send_frame(connection, {"ok": True, "type": point.typename})
        sent_drops = 0
        try:
            while not self._closed:
                taken = sink.take(0.5)
                if taken is None:
                    send_frame(connection, {"idle": True})  # also finds out whether the looker is still there
                    continue
                stamp, item = taken
                dropped, sent_drops = sink.dropped - sent_drops, sink.dropped
                if wants_data:
                    send_frame(connection, {"t": stamp, "dropped": dropped}, item)
                    sink.give_back(item)
                else:
                    size, header_stamp = item
                    send_frame(connection, {"t": stamp, "dropped": dropped, "size": size, "stamp": header_stamp})
        finally:
            point.detach(sink)

    def _subscriptions(self, topic: str) -> list[Any]:
        return [entity for node in list(self.graph.nodes.values()) for entity in node.entities()
                if getattr(entity, "topic", None) == topic and hasattr(entity, "inject")]

    def _op_pub(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        topic, typename = _text(request, "topic"), _text(request, "type")
        reached = self._subscriptions(topic)
        wrong = sorted({s.typename for s in reached if s.typename != typename})
        if wrong:
            raise InspectError(f"{topic} carries {', '.join(wrong)}, not {typename}: publish a message of its type")
        wait = _number(request, "wait", 0.0, 0.0, 3600.0)
        message = self._codec(typename).decode(memoryview(payload))
        owed = [subscription.inject(message) for subscription in reached]
        if wait:
            self._await_handled(topic, reached, owed, wait)
        send_frame(connection, {"ok": True, "subscriptions": [s.node.name for s in reached]})

    def _op_settle(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        """Answer once the subscriptions of a topic here have handled every message published into them."""
        topic = _text(request, "topic")
        reached = self._subscriptions(topic)
        self._await_handled(topic, reached, [s.injected_handled_at for s in reached],
                            _number(request, "wait", 10.0, 0.0, 3600.0))
        send_frame(connection, {"ok": True})

    def _await_handled(self, topic: str, reached: list[Any], owed: list[int], wait: float) -> None:
        """Wait until each subscription's handled count reaches what it owes (a node that left is owed nothing)."""
        deadline = time.monotonic() + wait
        while busy := [s.node.name for s, due in zip(reached, owed, strict=True)
                       if s.stats.count < due and s.node.graph is self.graph and s.node.name in self.graph.nodes]:
            if time.monotonic() > deadline:
                raise InspectError(f"{', '.join(busy)} did not finish the messages of {topic} within {wait:g} s")
            time.sleep(0.0002)

    def _service(self, name: str) -> tuple[Node, ServiceType, Callable[[Any], Any], bool]:
        """(node, type, handler, whether it runs in the node's executor) of the server of ``name`` here: a
        service a node created, else a node's parameter service (every node answers those; the project
        file's parameters are answered at once, even by a node that does not spin, while an rclpy node's
        parameters go through its callbacks, between its other callbacks)."""
        nodes = list(self.graph.nodes.values())
        for node in nodes:
            for entity in node.entities():
                if getattr(entity, "name", None) == name and hasattr(entity, "handler"):
                    return node, entity.srv_type, entity.handle, True
        for node in nodes:
            if (found := node.parameter_services.get(name)) is not None:
                return node, *found, not isinstance(node.parameter_access, ProjectParameters)
            if node.lifecycle is not None and (found := node.lifecycle.services.get(name)) is not None:
                return node, *found, True  # transitions run the node's callbacks: in its executor
        raise InspectError(f"no server of {name} runs in {self.process} (yet)")

    def _op_call(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        node, srv_type, handle, in_executor = self._service(_text(request, "service"))
        timeout = _number(request, "timeout", 10.0, 1e-3, 3600.0)
        request_message = self._codec(f"{srv_type.name}_Request").decode(memoryview(payload))
        response = (node.call_in_executor(lambda: handle(request_message), timeout) if in_executor
                    else handle(request_message))
        send_frame(connection, {"ok": True}, self._codec(f"{srv_type.name}_Response").encode(response))

    def _op_send_goal(self, connection: socket.socket, request: dict[str, Any], payload: bytes) -> None:
        action = _text(request, "action")
        timeout = _number(request, "timeout", 600.0, 1e-3, 86_400.0)
        node = next((n for n in list(self.graph.nodes.values()) if action in n.action_servers), None)
        if node is None:
            raise InspectError(f"no server of action {action} runs in {self.process} (yet)")
        server = node.action_servers[action]
        goal = self._codec(f"{server.type.name}_Goal").decode(memoryview(payload))
        feedback: queue.SimpleQueue[Any] = queue.SimpleQueue()
        wants_feedback = bool(request.get("feedback", False))

        def submit() -> Any:  # in the node's executor: the listener is in place before execution starts
            handle = server.submit(goal)
            if handle is not None and wants_feedback:
                handle.feedback_listeners.append(feedback.put)
            return handle

        handle = node.call_in_executor(submit, 30.0)
        if handle is None:
            send_frame(connection, {"accepted": False})
            return
        send_frame(connection, {"accepted": True, "goal_id": handle.goal_id.hex()})
        encode_feedback = self._codec(f"{server.type.name}_Feedback").encode
        deadline = time.monotonic() + timeout
        while (handle._open or not feedback.empty()) and time.monotonic() < deadline and not self._closed:
            try:
                sent = feedback.get(timeout=0.01)
            except queue.Empty:
                continue
            send_frame(connection, {"feedback": True}, encode_feedback(sent))
        if handle._open:
            raise InspectError(f"goal {handle.goal_id.hex()[:8]} of {action} did not end within {timeout:g} s")
        result = handle.result if handle.result is not None else server.type.Result()
        send_frame(connection, {"status": int(handle.status)}, self._codec(f"{server.type.name}_Result").encode(result))


def _text(request: dict[str, Any], key: str) -> str:
    """A name field of a control request: refused, to the client, unless it is short text."""
    value = request.get(key)
    if not isinstance(value, str) or not 0 < len(value) <= 1024:
        raise InspectError(f"control request field {key!r} must be a name (text, 1..1024 characters), "
                           f"not {value!r:.80}")
    return value


def _number(request: dict[str, Any], key: str, default: float, low: float, high: float) -> float:
    """A numeric field of a control request: finite and within ``low..high``, else refused to the client."""
    value = request.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or not low <= value <= high:
        raise InspectError(f"control request field {key!r} must be a number in {low:g}..{high:g}, not {value!r:.80}")
    return float(value)
