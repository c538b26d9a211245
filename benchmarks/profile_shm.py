"""Where the time of one shared-memory hop goes, without wake-ups (both sides in one process).

    python benchmarks/profile_shm.py [payload bytes]

Prints microseconds per hop (publish + take) of a ``sensor_msgs/Image`` (plain and loaned
publish) and of a ``std_msgs/String``, beside the iceoryx2 binding alone doing what a hop
must (loan a slice, copy the payload in, send, receive, view it as a numpy array), and the
ratio of each to that floor; then the generated codec's encode/decode beside rosbags'.
These are the Python costs that remain once the adaptive spin has removed the wake-up.

The machines this runs on are noisy in phases of seconds (the same loop measured 7 µs and
12 µs a minute apart), so variants are interleaved in short rounds and each reports its
fastest round: noise only ever adds time.
"""

from __future__ import annotations

import ctypes
import os
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from hetros import Node
from hetros.msg import registry
from hetros.plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan
from hetros.runtime import Graph
from hetros.transport import QoS, remove_session_segments
from hetros.transport.shm._iceoryx import iox2

N = 1000
ROUNDS = int(os.environ.get("ROUNDS", "25"))
TOPICS = {"/image": "sensor_msgs/msg/Image", "/string": "std_msgs/msg/String"}


def fastest_round(variants: dict[str, Callable[[], object]]) -> dict[str, float]:
    """Microseconds per call of each variant: the fastest of ROUNDS interleaved rounds."""
    best = dict.fromkeys(variants, float("inf"))
    for _ in range(ROUNDS):
        for name, fn in variants.items():
            start = time.perf_counter()
            for _ in range(N):
                fn()
            best[name] = min(best[name], (time.perf_counter() - start) / N * 1e6)
    return best


def _plan() -> Plan:
    qos = QoS(depth=16, publish_timeout=30.0)
    return Plan(
        "profile", "/", (),
        {"p0": TargetPlan("p0", "process"), "p1": TargetPlan("p1", "process")},
        {"ping": NodePlan("ping", "m:f", "p0", publish=dict(TOPICS)),
         "echo": NodePlan("echo", "m:f", "p1", subscribe=dict(TOPICS))},
        {topic: ChannelPlan(topic, kind, "topic", qos, ("ping",), ("echo",)) for topic, kind in TOPICS.items()},
        tuple(EdgePlan(topic, "ping", "echo", "shm") for topic in TOPICS),
    )


def _raw_binding_hop(session: str, payload: np.ndarray[Any, Any]) -> Callable[[], object]:
    """One hop through the iceoryx2 binding alone: the floor a framework on it cannot beat."""
    node = iox2.NodeBuilder.new().name(iox2.NodeName.new(f"hetros-profile-{os.getpid()}")).create(iox2.ServiceType.Ipc)
    service = (node.service_builder(iox2.ServiceName.new(f"hetros/{session}/raw"))
               .publish_subscribe(iox2.Slice[ctypes.c_uint8]).open_or_create())
    publisher = service.publisher_builder().initial_max_slice_len(payload.size + 64).create()
    subscriber = service.subscriber_builder().create()
    size = payload.size

    def hop() -> None:
        sample = publisher.loan_slice_uninit(size)
        memory = (ctypes.c_uint8 * size).from_address(sample.payload_ptr)
        ctypes.memmove(memory, payload.ctypes.data, size)
        sample.assume_init().send()
        received = subscriber.receive()
        np.frombuffer((ctypes.c_uint8 * size).from_address(received.payload_ptr), np.uint8)

    hop.keep = (node, service, publisher, subscriber)  # type: ignore[attr-defined]
    return hop


def main() -> None:
    size = int(sys.argv[1]) if len(sys.argv) > 1 else 4
    session = f"{os.getpid()}xprofile"
    publisher_graph = Graph(_plan(), "p0", session)
    subscriber_graph = Graph(_plan(), "p1", session)
    subscriber_graph.prepare(["echo"])
    types = registry()
    Image, String = types.get("sensor_msgs/msg/Image"), types.get("std_msgs/msg/String")
    ping, echo = Node("ping", publisher_graph), Node("echo", subscriber_graph)
    image_out, string_out = ping.create_publisher(Image, "/image"), ping.create_publisher(String, "/string")
    image_in, string_in = echo.create_subscription(Image, "/image"), echo.create_subscription(String, "/string")
    payload = np.zeros(size, np.uint8)
    payload.flags.writeable = False  # the user's frame, handed over without a copy in a process
    text = "x" * size

    def image_hop(loaned: bool) -> Callable[[], object]:
        def once() -> None:
            if loaned:
                message = image_out.loan(data=size)
                np.copyto(message.data, payload)
            else:
                message = Image(data=payload)
            message.header.stamp.sec, message.height = 1, 1
            image_out.publish(message)
            image_in.try_take()
        return once

    def string_hop() -> None:
        string_out.publish(String(data=text))
        string_in.try_take()

    try:
        hop = fastest_round({"Image, plain publish": image_hop(False), "Image, loaned publish": image_hop(True),
                             "String": string_hop, "iceoryx2 binding alone": _raw_binding_hop(session, payload)})
        floor = hop["iceoryx2 binding alone"]
        print(f"| one hop at {size} B, publish + take | µs | / binding alone |")
        print("|---|---|---|")
        for name, micros in hop.items():
            print(f"| {name} | {micros:.1f} | {micros / floor:.1f}x |")
        image = Image(data=np.zeros(size, np.uint8))
        raw = types.serialize(image)
        codec = types.codec("sensor_msgs/msg/Image")
        buffer = memoryview(bytearray(len(raw)))
        body = raw[4:].toreadonly()
        codecs = fastest_round({
            "encode": lambda: codec.encode(image, buffer), "decode": lambda: codec.decode(body),
            "serialize": lambda: types.serialize(image),
            "deserialize": lambda: types.deserialize(raw, image.__msgtype__),
        })
        print(f"\n{size} B Image: generated encode {codecs['encode']:5.1f} µs, decode {codecs['decode']:5.1f} µs; "
              f"rosbags serialize {codecs['serialize']:5.1f} µs, deserialize {codecs['deserialize']:5.1f} µs")
    finally:
        ping.close()
        echo.close()
        publisher_graph.close()
        subscriber_graph.close()
        remove_session_segments(session)


if __name__ == "__main__":
    main()
