"""One process' presence in a ROS 1 graph: its slave API, its TCPROS publications and subscriptions.

Registration stays in software and happens once (master API over XML-RPC, then
``requestTopic`` and one connection header per connection); after that every message is
one frame: a 4-byte little-endian length and the ROS 1 bytes, written with one vectored
``sendmsg`` on a TCP_NODELAY socket. A peer that sends garbage is disconnected and logged;
the node goes on. A master that is down is retried (logged); running connections survive
the master going away, as in ROS 1.
"""

from __future__ import annotations

import functools
import os
import socket
import threading
import time
import xmlrpc.client
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from ..._errors import ProtocolError, PublishTimeoutError, SerializationError, ServiceTimeoutError, TransportError
from ..._log import get_logger
from ..._qos import QoS
from ._admission import Admission
from ._header import FRAME, decode_header, encode_header, frame_length, header_length, require
from ._outgoing import SubscriberLink, send_parts
from ._types import Payload, Ros1Kind, Ros1ServiceType
from ._xmlrpc import CALL_TIMEOUT, proxy, serve

log = get_logger("hetros.ros1")

# connections accepted but not yet past their header; beyond them a new one waits a second, then is closed
MAX_HANDSHAKES = 64
# threads of one node that reach announced publishers (requestTopic and the header) at once
MAX_CONNECTORS = 8




def get_ros1_parameter(master_uri: str, caller_id: str, key: str) -> Any:
    """A parameter from a ROS 1 parameter server (``~x`` is private to ``caller_id``); KeyError if unset."""
    if key.startswith("~"):
        key = caller_id.rstrip("/") + "/" + key[1:]
    elif not key.startswith("/"):
        key = "/" + key
    try:
        code, _message, value = proxy(master_uri).getParam(caller_id, key)
    except (OSError, xmlrpc.client.Error) as exc:
        raise TransportError(f"the ROS master at {master_uri} is unreachable ({exc}); cannot read {key}") from None
    if code != 1:
        raise KeyError(key)
    return value


# frames up to this size are read into a fresh bytes object; larger ones into untouched memory
_SMALL = 1 << 16


def _receive_exactly(sock: socket.socket, size: int) -> bytes | memoryview:
    """``size`` bytes from ``sock``. A large frame lands in memory the kernel maps page by page as
    bytes arrive: a peer whose length prefix lies costs what it sent, not what it announced."""
    if size <= _SMALL:
        data = sock.recv(size, socket.MSG_WAITALL)
        if len(data) == size:
            return data
        if not data:
            raise ConnectionError(f"connection closed after 0 of {size} bytes")
        view = memoryview(bytearray(size))
        view[:len(data)] = data
        got = len(data)
    else:
        view = memoryview(np.empty(size, np.uint8).data)
        got = 0
    while got < size:
        count = sock.recv_into(view[got:], size - got)
        if not count:
            raise ConnectionError(f"connection closed after {got} of {size} bytes")
        got += count
    return view


def _same_type(name: str, peer: str, fields: dict[str, str], kind: str, md5: str) -> None:
    """Refuse a peer whose md5sum differs (``*`` matches any), naming both types and md5s."""
    if fields["md5sum"] not in (md5, "*"):
        raise ProtocolError(f"{name}: {peer} has {fields.get('type', '?')} (md5 {fields['md5sum']}), "
                            f"this node has {kind} (md5 {md5})")


def _frame_length(prefix: bytes | memoryview, peer: str) -> int:
    (length,) = FRAME.unpack(prefix)
    return frame_length(length, peer)


def read_header(sock: socket.socket, peer: str) -> dict[str, str]:
    length = header_length(bytes(_receive_exactly(sock, 4)), peer)
    return decode_header(bytes(_receive_exactly(sock, length)), peer)


def _configure(sock: socket.socket) -> None:
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


# what a publication to ROS 1 does with a subscriber that falls behind, unless told otherwise
ROS1_QOS = QoS(reliability="reliable", history="keep_last", depth=10)


class Ros1Publication:
    """A topic this process publishes to ROS 1 subscribers (see SubscriberLink for slow ones)."""

    def __init__(self, peer: Ros1Peer, topic: str, kind: Ros1Kind, latch: bool, qos: QoS = ROS1_QOS) -> None:
        self.peer = peer
        self.topic = topic
        self.kind = kind
        self.latch = latch
        self.qos = qos
        self._lock = threading.Lock()
        self._links: list[SubscriberLink] = []
        self._latched: list[Payload] | None = None
        self.sent = 0

    def publish(self, message: Any) -> None:
        """Serialize once, one vectored write per subscriber; a subscriber that went away is dropped.

        A large array goes from the message's memory to the socket (``serialize_parts``);
        whatever a subscriber cannot take at once is copied, so the caller may reuse its
        buffer after ``publish``. A latched message is kept as one copy of its own.
        """
        parts = self.kind.serialize_parts(message)
        total = sum(len(part) for part in parts)
        self._send([FRAME.pack(total), *parts], total + FRAME.size)

    def publish_frame(self, frame: Payload) -> None:
        """Send a whole TCPROS frame, its length included, as it is (hardware TCPROS: the fpga target's
        framer made it); the caller may reuse ``frame`` afterwards."""
        if len(frame) < FRAME.size or FRAME.unpack(frame[:FRAME.size])[0] != len(frame) - FRAME.size:
            raise ProtocolError(f"a frame for {self.topic} must start with its length ({len(frame) - FRAME.size}), "
                                f"not {bytes(frame[:FRAME.size]).hex()}")
        self._send([frame], len(frame))

    def _send(self, frame: list[Payload], total: int) -> None:
        timeout: PublishTimeoutError | None = None
        with self._lock:
            if self.latch:
                self._latched = [b"".join(frame)]
            for link in list(self._links):
                try:
                    link.send(frame, total)
                except PublishTimeoutError as exc:
                    timeout = exc
                except OSError as exc:
                    log.info("ROS 1 subscriber %s of %s went away (%s)", link.who, self.topic, exc)
                    self._drop(link)
            self.sent += 1
        if timeout is not None:
            raise timeout

    def _add(self, sock: socket.socket, who: str) -> None:
        link = SubscriberLink(sock, who, self.topic, self.qos)
        with self._lock:
            if self._latched is not None:
                link.send(self._latched, len(self._latched[0]))
            self._links.append(link)

    def _drop(self, link: SubscriberLink) -> None:
        self._links = [other for other in self._links if other is not link]
        link.close()

    @property
    def subscribers(self) -> list[str]:
        with self._lock:
            return [link.who for link in self._links]

    def close(self) -> None:
        with self._lock:
            links, self._links = self._links, []
        for link in links:
            link.close()


def hang_up(sock: socket.socket) -> None:
    """End a connection that another thread reads: its read sees the end and that thread closes it."""
    try:
        sock.shutdown(socket.SHUT_RDWR)
    except OSError:
        pass


# what a subscription does with a connection past its header: (socket, peer description, gone)
Attach = Callable[[socket.socket, str, Callable[[], None]], None]


class Ros1Subscription:
    """A topic this process receives from ROS 1 publishers.

    Each publisher's connection is made (``requestTopic``, headers) on a thread of its own;
    then ``attach`` takes it over: :meth:`Ros1Peer.subscribe`'s attach reads it on that
    thread and calls back per message (the bridge), a node's stream reader reads it in
    the node's thread (``kind: ros1`` nodes).
    """

    def __init__(self, peer: Ros1Peer, topic: str, kind: Ros1Kind, attach: Attach) -> None:
        self.peer = peer
        self.topic = topic
        self.kind = kind
        self._attach = attach
        self._lock = threading.Lock()
        self._connections: dict[str, socket.socket] = {}

    def update(self, publishers: list[str]) -> None:
        """Connect to new publishers (slave API URIs), drop those that left."""
        with self._lock:
            gone = [uri for uri in self._connections if uri not in publishers]
            for uri in gone:
                hang_up(self._connections.pop(uri))
            new = [uri for uri in publishers if uri not in self._connections and uri != self.peer.uri]
        for uri in new:  # a few threads for the whole node, however many publishers are announced
            self.peer.connect_later(functools.partial(self._connect, uri))

    def _connect(self, publisher: str) -> None:
        try:
            code, message, protocol = proxy(publisher).requestTopic(self.peer.name, self.topic, [["TCPROS"]])
            if code != 1 or not protocol or protocol[0] != "TCPROS":
                log.warning("ROS 1 publisher %s refused %s over TCPROS: %s", publisher, self.topic, message)
                return
            _name, host, port = protocol
            sock = socket.create_connection((host, int(port)), timeout=CALL_TIMEOUT)
        except (OSError, xmlrpc.client.Error, ValueError) as exc:
            log.warning("cannot reach the ROS 1 publisher %s of %s: %s", publisher, self.topic, exc)
            return
        peer = f"ROS 1 publisher {publisher} of {self.topic}"
        try:
            _configure(sock)
            sock.sendall(encode_header({
                "callerid": self.peer.name, "topic": self.topic, "md5sum": self.kind.md5, "type": self.kind.name,
                "message_definition": self.kind.definition, "tcp_nodelay": "1",
            }))
            fields = read_header(sock, peer)
            require(fields, ("md5sum", "type"), peer)
            _same_type(self.topic, peer, fields, self.kind.name, self.kind.md5)
            sock.settimeout(None)
        except (OSError, ProtocolError) as exc:
            log.error("%s", exc)
            sock.close()
            return
        with self._lock:
            self._connections[publisher] = sock

        def gone() -> None:
            with self._lock:
                if self._connections.get(publisher) is sock:
                    del self._connections[publisher]

        # a live connection is read on a thread of its own (the bridge's receive loop lasts as long
        # as the connection): the connecting threads stay free for the next publisher
        threading.Thread(target=self._attach, args=(sock, peer, gone), name=f"hetros-ros1-in {self.topic}",
                         daemon=True).start()

    @property
    def publishers(self) -> list[str]:
        with self._lock:
            return list(self._connections)

    def close(self) -> None:
        with self._lock:
            for sock in self._connections.values():
                hang_up(sock)
            self._connections.clear()


def receive_loop(kind: Ros1Kind, callback: Callable[[Any], None]) -> Attach:
    """An ``attach`` that reads a connection on its connecting thread, ``callback`` per message."""

    def attach(sock: socket.socket, peer: str, gone: Callable[[], None]) -> None:
        try:
            while True:
                length = _frame_length(_receive_exactly(sock, 4), peer)
                callback(kind.deserialize(_receive_exactly(sock, length)))
        except (ProtocolError, SerializationError) as exc:
            log.error("%s; disconnected", exc)
        except OSError:
            pass  # the publisher went away or we closed the connection
        finally:
            gone()
            sock.close()

    return attach


def receive_frames(callback: Callable[[bytes], None]) -> Attach:
    """An ``attach`` handing on each frame as it came, its length included (hardware TCPROS: the fpga
    target's deframer reads it): no message is built in software. A frame announcing more than
    ``MAX_FRAME`` bytes closes the connection, with a logged error."""

    def attach(sock: socket.socket, peer: str, gone: Callable[[], None]) -> None:
        try:
            while True:
                prefix = bytes(_receive_exactly(sock, 4))
                callback(prefix + bytes(_receive_exactly(sock, _frame_length(prefix, peer))))
        except ProtocolError as exc:
            log.error("%s; disconnected", exc)
        except OSError:
            pass
        finally:
            gone()
            sock.close()

    return attach


class Ros1Peer:
    """A ROS 1 node as other ROS 1 nodes see it: a name, a slave API, a TCPROS port."""

    def __init__(self, name: str, master_uri: str, host: str = "127.0.0.1",
                 stop: threading.Event | None = None) -> None:
        self.name = name if name.startswith("/") else "/" + name
        self.master_uri = master_uri
        self.host = host
        self._master = proxy(master_uri)
        self._publications: dict[str, Ros1Publication] = {}
        self._subscriptions: dict[str, Ros1Subscription] = {}
        self._services: dict[str, tuple[Ros1ServiceType, Callable[[Any], Any]]] = {}
        self._lock = threading.Lock()
        self._closed = False
        self._stop = stop
        self._handshakes = Admission(f"ROS 1 node {self.name} (TCPROS/ROSRPC)", MAX_HANDSHAKES, CALL_TIMEOUT)
        self._to_connect: deque[Callable[[], None]] = deque()
        self._connectors = 0
        self._slave = serve(host, 0, _SlaveApi(self))
        self.uri = f"http://{host}:{self._slave.server_address[1]}/"
        self._tcpros = socket.create_server((host, 0))
        self.tcpros_port = self._tcpros.getsockname()[1]
        self._rosrpc_uri = f"rosrpc://{host}:{self.tcpros_port}"
        self._threads = [
            threading.Thread(target=self._slave.serve_forever, name="hetros-ros1-slave", daemon=True),
            threading.Thread(target=self._accept, name="hetros-ros1-accept", daemon=True),
        ]
        for thread in self._threads:
            thread.start()

    def connect_later(self, connect: Callable[[], None]) -> None:
        """Run ``connect`` (reaching one publisher) on one of at most ``MAX_CONNECTORS`` threads:
        a ``publisherUpdate`` naming a thousand dead publishers costs a few threads, not a thousand."""
        with self._lock:
            self._to_connect.append(connect)
            if self._connectors >= MAX_CONNECTORS:
                return
            self._connectors += 1
        threading.Thread(target=self._connecting, name="hetros-ros1-connect", daemon=True).start()

    def _connecting(self) -> None:
        while True:
            with self._lock:
                if not self._to_connect or self._closed:
                    self._connectors -= 1
                    return
                connect = self._to_connect.popleft()
            connect()

    # -- master ----------------------------------------------------------------------------

    def _call_master(self, method: str, *args: Any, retry_for: float = 30.0) -> Any:
        """One master API call; a master that is down is retried with a log line, for ``retry_for`` s."""
        deadline = time.monotonic() + retry_for
        logged = False
        while True:
            try:
                code, message, value = getattr(self._master, method)(self.name, *args)
            except OSError as exc:
                if time.monotonic() > deadline or self._closed or (self._stop is not None and self._stop.is_set()):
                    raise TransportError(f"the ROS master at {self.master_uri} is unreachable ({exc}); start "
                                         "`hetros master` or roscore, or fix ROS_MASTER_URI") from None
                if not logged:
                    log.warning("ROS master at %s unreachable (%s); retrying for %g s: start `hetros master` "
                                "or roscore there, or fix external.ros1.master / ROS_MASTER_URI",
                                self.master_uri, exc, retry_for)
                    logged = True
                time.sleep(0.5)
                continue
            if code != 1:
                raise TransportError(f"the ROS master refused {method}{args[:2]}: {message}")
            return value

    # -- endpoints -------------------------------------------------------------------------

    def advertise(self, topic: str, kind: Ros1Kind, latch: bool = False, qos: QoS = ROS1_QOS) -> Ros1Publication:
        publication = Ros1Publication(self, topic, kind, latch, qos)
        with self._lock:
            self._publications[topic] = publication
        self._call_master("registerPublisher", topic, kind.name, self.uri)
        return publication

    def subscribe(self, topic: str, kind: Ros1Kind, callback: Callable[[Any], None] | None = None, *,
                  attach: Attach | None = None) -> Ros1Subscription:
        """Receive ``topic``: ``callback`` per message on the connection's thread, or each connection
        handed to ``attach`` once its header is through (a node's stream reader)."""
        if attach is None:
            if callback is None:
                raise TypeError("subscribe needs a callback or an attach function")
            attach = receive_loop(kind, callback)
        subscription = Ros1Subscription(self, topic, kind, attach)
        with self._lock:
            self._subscriptions[topic] = subscription
        publishers = self._call_master("registerSubscriber", topic, kind.name, self.uri)
        subscription.update(list(publishers))
        return subscription

    def advertise_service(self, service: str, kind: Ros1ServiceType, handler: Callable[[Any], Any]) -> None:
        """Serve ``service`` to ROS 1 clients (ROSRPC): ``handler(request)`` returns the response."""
        with self._lock:
            self._services[service] = (kind, handler)
        self._call_master("registerService", service, self._rosrpc_uri, self.uri)

    def call_service(self, service: str, kind: Ros1ServiceType, request: Any, timeout: float = 10.0) -> Any:
        """Call a ROS 1 service once (a fresh connection, as rospy's default) and return the response."""
        uri = self._call_master("lookupService", service, retry_for=0.0)
        host, _, port = str(uri).removeprefix("rosrpc://").rstrip("/").rpartition(":")
        peer = f"ROS 1 service {service} at {uri}"
        try:
            with socket.create_connection((host, int(port)), timeout=timeout) as sock:
                _configure(sock)
                sock.sendall(encode_header({"callerid": self.name, "service": service, "md5sum": kind.md5,
                                            "persistent": "0"}))
                fields = read_header(sock, peer)
                require(fields, ("md5sum",), peer)
                _same_type(service, peer, fields, kind.name, kind.md5)
                payload = kind.request.serialize(request)
                send_parts(sock, [FRAME.pack(len(payload)), payload])
                ok = _receive_exactly(sock, 1)[0]
                body = _receive_exactly(sock, _frame_length(_receive_exactly(sock, 4), peer))
        except TimeoutError:
            raise ServiceTimeoutError(f"ROS 1 service {service} did not answer within {timeout:g} s") from None
        except OSError as exc:
            raise TransportError(f"calling {peer} failed: {exc}") from None
        if not ok:
            raise TransportError(f"ROS 1 service {service} failed: {bytes(body).decode(errors='replace')}")
        return kind.response.deserialize(body)

    # -- TCPROS server ---------------------------------------------------------------------

    def _accept(self) -> None:
        while not self._closed:
            try:
                sock, address = self._tcpros.accept()
            except OSError:
                return
            self._handshakes.enter(sock, f"{address[0]}:{address[1]}")
            threading.Thread(target=self._handshake, args=(sock, f"{address[0]}:{address[1]}"),
                             name="hetros-ros1-handshake", daemon=True).start()

    def _handshake(self, sock: socket.socket, address: str) -> None:
        peer = f"ROS 1 connection from {address}"
        introduced = threading.Event()

        def done() -> None:
            """The header exchange is over: free its slot (a persistent service connection lives on)."""
            if not introduced.is_set():
                introduced.set()
                self._handshakes.leave(sock)

        try:
            self._introduce(sock, address, peer, done)
        finally:
            done()

    def _introduce(self, sock: socket.socket, address: str, peer: str, done: Callable[[], None]) -> None:
        try:
            sock.settimeout(CALL_TIMEOUT)
            fields = read_header(sock, peer)
            if "service" in fields:
                self._serve(sock, fields, address, done)
                return
            require(fields, ("callerid", "topic", "md5sum", "type"), peer)
            peer = f"ROS 1 subscriber {fields['callerid']} ({address})"
            with self._lock:
                publication = self._publications.get(fields["topic"])
            if publication is None:
                raise ProtocolError(f"{peer} asked for {fields['topic']}, which this node does not publish")
            kind = publication.kind
            _same_type(fields['topic'], peer, fields, kind.name, kind.md5)
            _configure(sock)
            sock.sendall(encode_header({
                "callerid": self.name, "md5sum": kind.md5, "type": kind.name, "topic": fields["topic"],
                "message_definition": kind.definition, "latching": "1" if publication.latch else "0",
            }))
            sock.settimeout(None)
            publication._add(sock, fields["callerid"])
        except (ProtocolError, SerializationError) as exc:
            log.error("%s; disconnected", exc)
            try:
                sock.sendall(encode_header({"error": str(exc)}))
            except OSError:
                pass
            sock.close()
        except OSError as exc:
            log.info("%s: %s", peer, exc)
            sock.close()

    def _serve(self, sock: socket.socket, fields: dict[str, str], address: str, done: Callable[[], None]) -> None:
        """One ROSRPC connection: answer its header, then each request until the client closes."""
        peer = f"ROS 1 client {fields.get('callerid', '?')} ({address})"
        require(fields, ("callerid", "service", "md5sum"), peer)
        service = fields["service"]
        with self._lock:
            entry = self._services.get(service)
        if entry is None:
            raise ProtocolError(f"{peer} asked for service {service}, which this node does not serve")
        kind, handler = entry
        _same_type(service, peer, fields, kind.name, kind.md5)
        _configure(sock)
        sock.sendall(encode_header({"callerid": self.name, "md5sum": kind.md5, "type": kind.name,
                                    "request_type": kind.request_name, "response_type": kind.response_name}))
        if fields.get("probe") == "1":
            sock.close()
            return
        done()
        try:
            while True:
                sock.settimeout(None)  # a persistent client may be quiet for long between calls
                try:
                    prefix = _receive_exactly(sock, 4)
                except ConnectionError:
                    return  # the client is done
                sock.settimeout(CALL_TIMEOUT)  # but a request it started must arrive in time
                request = kind.request.deserialize(_receive_exactly(sock, _frame_length(prefix, peer)))
                try:
                    payload = kind.response.serialize(handler(request))
                    send_parts(sock, [b"\x01", FRAME.pack(len(payload)), payload])
                except (ProtocolError, OSError):
                    raise
                except Exception as exc:  # the handler's failure goes back to the caller, as in ROS 1
                    log.error("service %s failed for %s: %s", service, peer, exc)
                    text = f"{type(exc).__name__}: {exc}".encode()
                    send_parts(sock, [b"\x00", FRAME.pack(len(text)), text])
        finally:
            sock.close()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        for topic, publication in list(self._publications.items()):
            self._unregister("unregisterPublisher", topic, self.uri)
            publication.close()
        for topic, subscription in list(self._subscriptions.items()):
            self._unregister("unregisterSubscriber", topic, self.uri)
            subscription.close()
        for service in list(self._services):
            self._unregister("unregisterService", service, self._rosrpc_uri)
        self._slave.shutdown()
        self._slave.server_close()
        self._tcpros.close()
        self._handshakes.close()

    def _unregister(self, method: str, name: str, api: str) -> None:
        try:
            getattr(self._master, method)(self.name, name, api)
        except (OSError, xmlrpc.client.Error):
            pass  # a master that is gone has nothing to unregister


class _SlaveApi:
    """The slave API other ROS 1 nodes and tools call (each returns ``[code, message, value]``)."""

    def __init__(self, peer: Ros1Peer) -> None:
        self._peer = peer

    def getMasterUri(self, caller_id: str) -> tuple[int, str, str]:
        return 1, "", self._peer.master_uri

    def getPid(self, caller_id: str) -> tuple[int, str, int]:
        return 1, "", os.getpid()

    def getSubscriptions(self, caller_id: str) -> tuple[int, str, list[list[str]]]:
        return 1, "subscriptions", [[t, s.kind.name] for t, s in self._peer._subscriptions.items()]

    def getPublications(self, caller_id: str) -> tuple[int, str, list[list[str]]]:
        return 1, "publications", [[t, p.kind.name] for t, p in self._peer._publications.items()]

    def getBusStats(self, caller_id: str) -> tuple[int, str, list[Any]]:
        publishing = [[t, p.sent, []] for t, p in self._peer._publications.items()]
        subscribing = [[t, []] for t in self._peer._subscriptions]
        return 1, "bus stats", [publishing, subscribing, []]

    def getBusInfo(self, caller_id: str) -> tuple[int, str, list[list[Any]]]:
        info: list[list[Any]] = []
        for topic, publication in self._peer._publications.items():
            info += [[len(info), who, "o", "TCPROS", topic, True] for who in publication.subscribers]
        for topic, subscription in self._peer._subscriptions.items():
            info += [[len(info), uri, "i", "TCPROS", topic, True] for uri in subscription.publishers]
        return 1, "bus info", info

    def paramUpdate(self, caller_id: str, key: str, value: Any) -> tuple[int, str, int]:
        return 1, "", 0

    def publisherUpdate(self, caller_id: str, topic: str, publishers: list[str]) -> tuple[int, str, int]:
        subscription = self._peer._subscriptions.get(topic)
        if subscription is not None:
            subscription.update(list(publishers))
        return 1, "", 0

    def requestTopic(self, caller_id: str, topic: str, protocols: list[list[Any]]) -> tuple[int, str, list[Any]]:
        if topic not in self._peer._publications:
            return -1, f"not a publisher of {topic}", []
        if not any(p and p[0] == "TCPROS" for p in protocols):
            return 0, "no supported protocol (only TCPROS)", []
        return 1, "", ["TCPROS", self._peer.host, self._peer.tcpros_port]

    def shutdown(self, caller_id: str, message: str = "") -> tuple[int, str, int]:
        log.warning("ROS 1 node %s asked to shut down by %s: %s; leaving the ROS 1 graph",
                    self._peer.name, caller_id, message)
        threading.Thread(target=self._peer.close, name="hetros-ros1-shutdown", daemon=True).start()
        return 1, "", 0
