"""Ping and echo roles of every benchmarked system, run as ``python -m hetros_bench._roles``.

Every system moves the same thing: a payload of N bytes plus a send timestamp and a
sequence number. The ping role stamps ``time.monotonic_ns()`` (one clock for every
process on the host) when it starts publishing; the echo role records the one-way
latency when it holds the message, copies the payload into a new message and sends
it back; ping records the round trip. Peers that carry raw bytes put stamp and
sequence number into a 16-byte prefix.
"""

from __future__ import annotations

import ctypes
import importlib
import json
import os
import queue
import struct
import sys
import threading
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

PREFIX = struct.Struct("<qq")
PROBE = -1
STOP = -2


class Endpoint(ABC):
    """One side of a ping-pong pair: send to the other side, receive from it."""

    @abstractmethod
    def send(self, stamp: int, seq: int, payload: Any) -> None: ...

    @abstractmethod
    def recv(self, timeout: float) -> tuple[int, int, Any] | None: ...

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        """Send back a copy of what was received (the copy is part of the measurement)."""
        self.send(stamp, seq, bytes(received) if not isinstance(received, np.ndarray) else received.copy())

    def payload(self, received: Any) -> Any:
        """The received payload as a buffer (to read every byte of it)."""
        return received

    def close(self) -> None:
        return None


def framed(size: int) -> bytearray:
    return bytearray(PREFIX.size + size)


# -- hetros ------------------------------------------------------------------------------

def _ping_pong() -> Any:
    """The library's ping-pong plan (the advisor's calibration runs the same), imported only by hetros's roles."""
    from hetros.advise import ping_pong_plan

    return ping_pong_plan(16)


class HetrosEndpoint(Endpoint):
    """A hetros node: inproc when both roles share a graph, shm across processes."""

    def close(self) -> None:
        self.node.close()
        self.node.graph.close()

    def __init__(self, role: str, graph: Any, loaned: bool, writes: bool = True) -> None:
        from hetros import Node, TakeTimeoutError
        from hetros.msg import registry

        Image = registry().get("sensor_msgs/msg/Image")
        self.Image = Image
        self.timed_out = TakeTimeoutError  # imported once: an import per message costs 0.27 µs
        self.node = Node(role, graph)
        out_topic, in_topic = ("/send", "/recv") if role == "ping" else ("/recv", "/send")
        self.pub = self.node.create_publisher(Image, out_topic)
        self.sub = self.node.create_subscription(Image, in_topic)
        self.loaned = loaned
        self._written: dict[int, Any] = {}  # the plain producer's own buffer per size, reused as real ones are
        # whether a plain producer writes its data in the timed section (shm); in one process (inproc) the
        # message is handed over as it is, so the row measures the transport alone
        self.writes = writes

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        # the producer writes its data once in either case, as a camera driver or a filter does: into the
        # loan (shared memory, sent as it is), or into a buffer of its own that publish then copies
        if self.loaned:
            msg = self.pub.loan(data=len(payload))
            np.copyto(msg.data, payload)
        elif not self.writes:
            msg = self.Image(data=payload)
        else:
            written = self._written.get(len(payload))
            if written is None:
                written = self._written[len(payload)] = np.empty(len(payload), np.uint8)
            np.copyto(written, payload)
            msg = self.Image(data=written)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.height = seq & 0xFFFFFFFF
        msg.width = 1 if seq < 0 else 0
        self.pub.publish(msg)

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        if self.loaned:
            msg = self.pub.loan(data=received.size)
            np.copyto(msg.data, received)
        else:
            copied = received.copy()
            copied.flags.writeable = False  # nobody can write it any more: handed over without another copy
            msg = self.Image(data=copied)
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.height = seq & 0xFFFFFFFF
        msg.width = 1 if seq < 0 else 0
        self.pub.publish(msg)

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        try:
            msg = self.sub.take(timeout=timeout)
        except self.timed_out:
            return None
        seq = msg.height if not msg.width else msg.height - (1 << 32)
        return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec, seq, msg.data


def open_hetros_shm(role: str, cfg: dict[str, Any], loaned: bool) -> Endpoint:
    from hetros.runtime import Graph

    graph = Graph(_ping_pong(), "p0" if role == "ping" else "p1", cfg["session"])
    if role == "echo":
        graph.prepare(["echo"])
    return HetrosEndpoint(role, graph, loaned)


# -- iceoryx2 used directly ----------------------------------------------------------------

class Iceoryx2Endpoint(Endpoint):
    """iceoryx2 publish-subscribe plus an event service: the same blocking wait as hetros."""

    def __init__(self, role: str, cfg: dict[str, Any]) -> None:
        from hetros.transport.shm import iox2, new_node

        self.iox2 = iox2
        # under hetros's root, so cleanup_stale reclaims it after a crash (the same settings otherwise)
        self.node = new_node(f"hetros-bench-{os.getpid()}")
        base = f"bench/{cfg['session']}"
        out_name, in_name = (f"{base}/send", f"{base}/recv") if role == "ping" else (f"{base}/recv", f"{base}/send")

        def pubsub(name: str) -> Any:
            return (self.node.service_builder(iox2.ServiceName.new(name))
                    .publish_subscribe(iox2.Slice[ctypes.c_uint8]).max_publishers(2).max_subscribers(2)
                    .subscriber_max_buffer_size(16).history_size(0).open_or_create())

        def event(name: str) -> Any:
            return self.node.service_builder(iox2.ServiceName.new(name + "/ev")).event().open_or_create()

        self.pub = (pubsub(out_name).publisher_builder().initial_max_slice_len(4096)
                    .allocation_strategy(iox2.AllocationStrategy.PowerOfTwo).create())
        self.sub = pubsub(in_name).subscriber_builder().create()
        self.notifier = event(out_name).notifier_builder().create()
        self.listener = event(in_name).listener_builder().create()
        self.ports: list[Any] = [self.pub, self.sub, self.notifier, self.listener]
        from hetros.runtime import AdaptiveSpin

        self.spin = AdaptiveSpin()  # the wait strategy of hetros' take: a like-for-like baseline

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        size = PREFIX.size + len(payload)
        sample = self.pub.loan_slice_uninit(size)
        PREFIX.pack_into((ctypes.c_uint8 * PREFIX.size).from_address(sample.payload_ptr), 0, stamp, seq)
        if len(payload):
            src = bytes(payload)
            ctypes.memmove(sample.payload_ptr + PREFIX.size, src, len(src))
        sample.assume_init().send()
        self.notifier.notify()

    def close(self) -> None:
        """Drop every iceoryx2 handle, so the node removes its shared memory before _exit."""
        self.ports.clear()
        del self.pub, self.sub, self.notifier, self.listener, self.node

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        data, size = received
        sample = self.pub.loan_slice_uninit(size)
        ctypes.memmove(sample.payload_ptr, data.payload_ptr, size)
        sample.assume_init().send()
        self.notifier.notify()

    def payload(self, received: Any) -> Any:
        sample, size = received
        return (ctypes.c_uint8 * (size - PREFIX.size)).from_address(sample.payload_ptr + PREFIX.size)

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        deadline = time.monotonic() + timeout
        started = time.perf_counter()
        spin = self.spin.budget(started)
        spin_end = started + spin
        while True:
            sample = self.sub.receive()
            if sample is not None:
                self.spin.arrived(time.perf_counter())
                size = sample.header.number_of_elements
                stamp, seq = PREFIX.unpack_from((ctypes.c_uint8 * PREFIX.size).from_address(sample.payload_ptr))
                return stamp, seq, (sample, size)
            if spin and time.perf_counter() < spin_end:
                continue
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            self.listener.timed_wait(self.iox2.Duration.from_secs_f64(left))


# -- multiprocessing.Pipe --------------------------------------------------------------------

class PipeEndpoint(Endpoint):
    def __init__(self, role: str, cfg: dict[str, Any]) -> None:
        from multiprocessing.connection import Connection

        read_fd, write_fd = cfg["fds"][role]
        self.rx = Connection(read_fd, writable=False)
        self.tx = Connection(write_fd, readable=False)

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        frame = framed(len(payload))
        PREFIX.pack_into(frame, 0, stamp, seq)
        frame[PREFIX.size:] = payload
        self.tx.send_bytes(frame)

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        self.tx.send_bytes(bytes(received))

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        if not self.rx.poll(timeout):
            return None
        data = self.rx.recv_bytes()
        stamp, seq = PREFIX.unpack_from(data)
        return stamp, seq, data


# -- zenoh -----------------------------------------------------------------------------------

class ZenohEndpoint(Endpoint):
    def __init__(self, role: str, cfg: dict[str, Any]) -> None:
        import zenoh

        conf = zenoh.Config()
        conf.insert_json5("mode", '"peer"')
        conf.insert_json5("scouting/multicast/enabled", "false")
        conf.insert_json5("scouting/gossip/enabled", "false")
        endpoint = f'["tcp/127.0.0.1:{cfg["port"]}"]'
        conf.insert_json5("listen/endpoints", endpoint if role == "ping" else "[]")
        conf.insert_json5("connect/endpoints", endpoint if role == "echo" else "[]")
        self.session: Any = zenoh.open(conf)
        out_key, in_key = ("bench/send", "bench/recv") if role == "ping" else ("bench/recv", "bench/send")
        self.pub = self.session.declare_publisher(out_key)
        self.inbox: queue.Queue[bytes] = queue.Queue()
        self.sub = self.session.declare_subscriber(in_key, lambda sample: self.inbox.put(sample.payload.to_bytes()))

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        frame = framed(len(payload))
        PREFIX.pack_into(frame, 0, stamp, seq)
        frame[PREFIX.size:] = payload
        self.pub.put(bytes(frame))

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        self.pub.put(bytes(received))

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        try:
            data = self.inbox.get(timeout=timeout)
        except queue.Empty:
            return None
        stamp, seq = PREFIX.unpack_from(data)
        return stamp, seq, data

    def close(self) -> None:
        session: Any = self.session
        session.close()


# -- CycloneDDS (Python binding) ----------------------------------------------------------------

class CycloneEndpoint(Endpoint):
    """The binding at its best: a fixed ``uint8`` array per size (one block copy)."""

    def __init__(self, role: str, cfg: dict[str, Any]) -> None:
        from cyclonedds.core import Policy, Qos
        from cyclonedds.domain import DomainParticipant
        from cyclonedds.pub import DataWriter
        from cyclonedds.sub import DataReader
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        from ._cyclone_types import payload_type

        Payload = payload_type(cfg["size"])
        self.Payload = Payload
        self.size = max(cfg["size"], 1)
        self.duration = duration
        qos = Qos(Policy.Reliability.Reliable(duration(seconds=10)), Policy.History.KeepLast(16))
        self.dp = DomainParticipant(cfg.get("domain", 0))
        out_name, in_name = ("rt/bench_send", "rt/bench_recv") if role == "ping" else ("rt/bench_recv", "rt/bench_send")
        self.writer = DataWriter(self.dp, Topic(self.dp, out_name, Payload), qos=qos)
        self.reader = DataReader(self.dp, Topic(self.dp, in_name, Payload), qos=qos)

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        data = bytes(payload)
        if len(data) != self.size:
            data = data.ljust(self.size, b"\0")[: self.size]
        self.writer.write(self.Payload(stamp=stamp, seq=seq, data=data))

    def echo(self, stamp: int, seq: int, received: Any) -> None:
        self.writer.write(self.Payload(stamp=stamp, seq=seq, data=bytes(received)))

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        try:
            sample = self.reader.take_one(timeout=self.duration(seconds=timeout))
        except Exception:
            return None
        return sample.stamp, sample.seq, sample.data


# -- driver ------------------------------------------------------------------------------------

# echo nodes written the ROS way (their ping side is hetros-shm's)
ROS_STYLE = {"hetros-rclpy-cb": "rclpy", "hetros-rospy-cb": "rospy"}
# both ends written the ROS way: the pinger too (hetros-shm-cb is the same pair in hetros's own API)
ROS_BOTH = {"hetros-rclpy-pp": "rclpy", "hetros-rospy-pp": "rospy"}
# both ends rospy, the pinger's callback publishing the next ping (its main thread only waits)
ROSPY_CALLBACK_PING = "hetros-rospy-pp-cb"


class RosPingEndpoint(Endpoint):
    """The pinger written the rclpy or the rospy way, as users port a ping-pong unchanged: a publisher, and
    a subscription callback that keeps the reply; rclpy spins the node until it comes, rospy's callback
    thread hands it over."""

    def __init__(self, cfg: dict[str, Any], flavour: str) -> None:
        from hetros import Node
        from hetros.compat import install
        from hetros.runtime import Graph, ros_main

        self.graph = Graph(_ping_pong(), "p0", cfg["session"])
        self.graph.prepare(["ping"])
        self.hetros = Node("ping", self.graph)
        install()
        self._bound = ros_main(self.hetros)
        self._bound.__enter__()
        self.flavour = flavour
        self.Image = importlib.import_module("sensor_msgs.msg").Image
        self.replies: list[Any] = []
        self._written: dict[int, Any] = {}
        if flavour == "rclpy":
            self.rclpy = importlib.import_module("rclpy")
            self.rclpy.init()
            self.node = self.rclpy.create_node("ping")
            self.pub = self.node.create_publisher(self.Image, "/send", 16)
            self.node.create_subscription(self.Image, "/recv", self.replies.append, 16)
        else:
            rospy = importlib.import_module("rospy")
            rospy.init_node("ping")
            self.arrived = threading.Event()
            self.pub = rospy.Publisher("/send", self.Image, queue_size=16)

            def on_reply(msg: Any) -> None:
                self.replies.append(msg)
                self.arrived.set()
            rospy.Subscriber("/recv", self.Image, on_reply, queue_size=16)

    def send(self, stamp: int, seq: int, payload: Any) -> None:
        msg = self.Image()
        msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
        msg.height, msg.width = seq & 0xFFFFFFFF, 1 if seq < 0 else 0
        written = self._written.get(len(payload))  # the producer writes its data, as HetrosEndpoint's does
        if written is None:
            written = self._written[len(payload)] = np.empty(len(payload), np.uint8)
        np.copyto(written, payload)
        msg.data = written
        self.pub.publish(msg)

    def recv(self, timeout: float) -> tuple[int, int, Any] | None:
        end = time.monotonic() + timeout
        while not self.replies:
            left = end - time.monotonic()
            if left <= 0:
                return None
            if self.flavour == "rclpy":
                self.rclpy.spin_once(self.node, timeout_sec=left)
            else:
                self.arrived.wait(left)
                self.arrived.clear()
        msg = self.replies.pop(0)
        seq = msg.height if not msg.width else msg.height - (1 << 32)
        return msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec, seq, msg.data

    def close(self) -> None:
        self._bound.__exit__(None, None, None)
        self.hetros.close()
        self.graph.close()


def rospy_callback_ping(cfg: dict[str, Any]) -> dict[str, Any]:
    """The pinger written the other way rospy nodes are: a subscription callback that publishes the next
    ping as soon as a reply comes, the main thread waiting until the last one, so that no reply is handed
    from the thread that receives it to another. Each round trip is timed from the moment its ping is
    built to the moment its reply's callback starts; probes and warm-up as in :func:`ping`."""
    from hetros import Node
    from hetros.compat import install
    from hetros.runtime import Graph, ros_main

    graph = Graph(_ping_pong(), "p0", cfg["session"])
    graph.prepare(["ping"])
    node = Node("ping", graph)
    install()
    rospy = importlib.import_module("rospy")
    Image = importlib.import_module("sensor_msgs.msg").Image
    payload = np.zeros(cfg["size"], np.uint8)
    written = np.empty(cfg["size"], np.uint8)  # the producer writes its data, as RosPingEndpoint's does
    total = cfg["warmup"] + cfg["reps"]
    rtt: list[int] = []
    started: list[int] = []  # when each numbered ping was built
    answered, finished = threading.Event(), threading.Event()

    with ros_main(node):
        rospy.init_node("ping")
        publisher = rospy.Publisher("/send", Image, queue_size=16)

        def send(seq: int) -> None:
            stamp = time.monotonic_ns()
            if seq >= 0:
                started.append(stamp)
            msg = Image()
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp, 1_000_000_000)
            msg.height, msg.width = seq & 0xFFFFFFFF, 1 if seq < 0 else 0
            if seq == STOP:
                msg.data = payload[:0]
            else:
                np.copyto(written, payload)
                msg.data = written
            publisher.publish(msg)

        def on_reply(msg: Any) -> None:
            now = time.monotonic_ns()
            seq = msg.height if not msg.width else msg.height - (1 << 32)
            if seq == PROBE:
                answered.set()
                return
            if seq != len(started) - 1 or finished.is_set():
                return
            if seq >= cfg["warmup"]:
                rtt.append(now - started[seq])
            if seq + 1 < total:
                send(seq + 1)
            else:
                finished.set()

        rospy.Subscriber("/recv", Image, on_reply, queue_size=16)
        deadline = time.monotonic() + cfg.get("connect_timeout", 30.0)
        while not answered.is_set():
            send(PROBE)
            if not answered.wait(0.2) and time.monotonic() > deadline:
                raise SystemExit(f"{cfg['system']}: the echo side never answered")
        time.sleep(0.05)  # the replies to the other probes
        send(0)
        if not finished.wait(600.0):
            raise SystemExit(f"{cfg['system']}: reply {len(started) - 1} lost")
        send(STOP)
        rospy.signal_shutdown("done")
    node.close()
    graph.close()
    return {"rtt_ns": rtt}


def open_endpoint(system: str, role: str, cfg: dict[str, Any]) -> Endpoint:
    if system in ("hetros-shm", "hetros-shm-cb", *ROS_STYLE):
        return open_hetros_shm(role, cfg, loaned=False)
    if system in ("hetros-shm-loan", "hetros-shm-loan-cb"):
        return open_hetros_shm(role, cfg, loaned=True)
    if system == "iceoryx2":
        return Iceoryx2Endpoint(role, cfg)
    if system == "mp-pipe":
        return PipeEndpoint(role, cfg)
    if system == "zenoh":
        return ZenohEndpoint(role, cfg)
    if system == "cyclonedds":
        return CycloneEndpoint(role, cfg)
    raise SystemExit(f"unknown system {system!r}")


def ping(endpoint: Endpoint, cfg: dict[str, Any]) -> dict[str, Any]:
    payload: Any = bytes(cfg["size"])
    if cfg["system"].startswith("hetros"):
        payload = np.zeros(cfg["size"], dtype=np.uint8)
        payload.flags.writeable = False  # the same frame every time: nobody writes it
    deadline = time.monotonic() + cfg.get("connect_timeout", 30.0)
    while True:
        endpoint.send(time.monotonic_ns(), PROBE, payload)
        if endpoint.recv(0.2) is not None:
            break
        if time.monotonic() > deadline:
            raise SystemExit(f"{cfg['system']}: the echo side never answered")
    while endpoint.recv(0.05) is not None:
        pass
    rtt: list[int] = []
    total = cfg["warmup"] + cfg["reps"]
    for seq in range(total):
        start = time.monotonic_ns()
        endpoint.send(start, seq, payload)
        while True:
            reply = endpoint.recv(10.0)
            if reply is None:
                raise SystemExit(f"{cfg['system']}: reply {seq} lost")
            if reply[1] == seq:
                break
        if seq >= cfg["warmup"]:
            rtt.append(time.monotonic_ns() - start)
        if cfg.get("gap"):
            time.sleep(cfg["gap"])
    endpoint.send(time.monotonic_ns(), STOP, payload[:0])
    return {"rtt_ns": rtt}


def echo(endpoint: Endpoint, cfg: dict[str, Any]) -> dict[str, Any]:
    one_way: list[int] = []
    while True:
        got = endpoint.recv(120.0)
        now = time.monotonic_ns()
        if got is None:
            raise SystemExit(f"{cfg['system']}: echo waited 120 s for a message")
        stamp, seq, data = got
        if seq == STOP:
            break
        if seq >= cfg["warmup"]:
            one_way.append(now - stamp)
        endpoint.echo(stamp, seq, data)
        del data, got
    return {"one_way_ns": one_way}


def callback_echo(cfg: dict[str, Any], loaned: bool) -> dict[str, Any]:
    """The echo node as users write it: a subscription callback that publishes a new message.

    The executor waits on the node's wake channel and runs the callback in the node's thread;
    plain publish copies the received array into a new message, loaned publish copies it
    into a loan.
    """
    from hetros import Node
    from hetros.msg import registry
    from hetros.runtime import Graph

    graph = Graph(_ping_pong(), "p1", cfg["session"])
    graph.prepare(["echo"])
    node = Node("echo", graph)
    image = registry().get("sensor_msgs/msg/Image")
    pub = node.create_publisher(image, "/recv")
    one_way: list[int] = []

    def on_ping(msg: Any) -> None:
        now = time.monotonic_ns()
        stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
        seq = msg.height if not msg.width else msg.height - (1 << 32)
        if seq == STOP:
            graph.shutdown()
            return
        if seq >= cfg["warmup"]:
            one_way.append(now - stamp)
        if loaned:
            out = pub.loan(data=msg.data.size)
            np.copyto(out.data, msg.data)
        else:
            out = image(data=msg.data.copy())
        out.header.stamp.sec, out.header.stamp.nanosec = msg.header.stamp.sec, msg.header.stamp.nanosec
        out.height, out.width = msg.height, msg.width
        pub.publish(out)

    node.create_subscription(image, "/send", on_ping)
    node.spin()
    node.close()
    graph.close()
    return {"one_way_ns": one_way}


def ros_echo(cfg: dict[str, Any], flavour: str) -> dict[str, Any]:
    """The echo node written the rclpy way or the rospy way, as users port it unchanged: a subscription
    callback that fills a new message from the received one and publishes it, through hetros's shims."""
    from hetros import Node
    from hetros.compat import install
    from hetros.runtime import Graph, ros_main

    graph = Graph(_ping_pong(), "p1", cfg["session"])
    graph.prepare(["echo"])
    node = Node("echo", graph)
    install()
    one_way: list[int] = []

    def arrived(msg: Any) -> bool:
        """Record the one-way time; False for the last message."""
        now = time.monotonic_ns()
        seq = msg.height if not msg.width else msg.height - (1 << 32)
        if seq == STOP:
            return False
        if seq >= cfg["warmup"]:
            one_way.append(now - (msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec))
        return True

    with ros_main(node):
        if flavour == "rclpy":
            _rclpy_echo(arrived)
        else:
            _rospy_echo(arrived)
    node.close()
    graph.close()
    return {"one_way_ns": one_way}


def _rclpy_echo(arrived: Callable[[Any], bool]) -> None:
    # what `import rclpy` and `from sensor_msgs.msg import Image` give inside hetros's processes
    rclpy = importlib.import_module("rclpy")
    Image = importlib.import_module("sensor_msgs.msg").Image

    class Echo(importlib.import_module("rclpy.node").Node):  # type: ignore[misc]
        def __init__(self) -> None:
            super().__init__("echo")
            self.publisher = self.create_publisher(Image, "/recv", 16)
            self.create_subscription(Image, "/send", self.on_ping, 16)

        def on_ping(self, msg: Any) -> None:
            if not arrived(msg):
                rclpy.shutdown()
                return
            out = Image()
            out.header = msg.header
            out.height, out.width = msg.height, msg.width
            out.data = msg.data
            self.publisher.publish(out)

    rclpy.init()
    rclpy.spin(Echo())


def _rospy_echo(arrived: Callable[[Any], bool]) -> None:
    rospy = importlib.import_module("rospy")
    Image = importlib.import_module("sensor_msgs.msg").Image

    rospy.init_node("echo")
    publisher = rospy.Publisher("/recv", Image, queue_size=16)

    def on_ping(msg: Any) -> None:
        if not arrived(msg):
            rospy.signal_shutdown("done")
            return
        publisher.publish(Image(header=msg.header, height=msg.height, width=msg.width, data=msg.data))

    rospy.Subscriber("/send", Image, on_ping, queue_size=16)
    rospy.spin()


def run_inproc(cfg: dict[str, Any]) -> dict[str, Any]:
    """Both roles as threads of one process on one hetros graph (the inproc transport).

    The process is pinned to one CPU, as a ``kind: process, cpus: [n]`` target would be:
    threads of one interpreter hand the GIL over, which across CPUs costs a wake-up each
    time (~60 µs here) and on one CPU a context switch (~5 µs).
    """
    from hetros.runtime import Graph

    graph = Graph.standalone()
    # plain publish of read-only arrays: in a process they travel with zero copies
    pinger = HetrosEndpoint("ping", graph, loaned=False, writes=False)
    echoer = HetrosEndpoint("echo", graph, loaned=False, writes=False)
    result: dict[str, Any] = {}

    def run_echo() -> None:
        if cfg.get("cpus"):
            os.sched_setaffinity(threading.get_native_id(), [cfg["cpus"][0]])
        result.update(echo(echoer, cfg))

    thread = threading.Thread(target=run_echo)
    thread.start()
    if cfg.get("cpus"):
        os.sched_setaffinity(threading.get_native_id(), [cfg["cpus"][0]])
    result.update(ping(pinger, cfg))
    thread.join()
    graph.close()
    return result


def main() -> None:
    system, role, cfg_path = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    cfg = json.loads(cfg_path.read_text())
    cfg["system"] = system
    if cfg.get("fds"):
        cfg["fds"] = {k: tuple(v) for k, v in cfg["fds"].items()}
    if role == "inproc":
        result = run_inproc(cfg)
    else:
        if cfg.get("cpus"):
            os.sched_setaffinity(0, [cfg["cpus"][0 if role == "ping" else 1]])
        if role == "echo" and system in ROS_STYLE | ROS_BOTH:
            result = ros_echo(cfg, (ROS_STYLE | ROS_BOTH)[system])
        elif role == "echo" and system == ROSPY_CALLBACK_PING:
            result = ros_echo(cfg, "rospy")
        elif role == "ping" and system == ROSPY_CALLBACK_PING:
            result = rospy_callback_ping(cfg)
        elif role == "ping" and system in ROS_BOTH:
            ros_pinger = RosPingEndpoint(cfg, ROS_BOTH[system])
            result = ping(ros_pinger, cfg)
            ros_pinger.close()
        elif role == "echo" and system.endswith("-cb"):
            result = callback_echo(cfg, loaned="loan" in system)
        else:
            endpoint = open_endpoint(system, role, cfg)
            result = ping(endpoint, cfg) if role == "ping" else echo(endpoint, cfg)
            endpoint.close()
    Path(cfg[f"{role}_out"]).write_text(json.dumps(result))
    os._exit(0)  # some peers' background threads would hold the interpreter at exit


if __name__ == "__main__":
    main()
