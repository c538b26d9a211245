"""hetros's side of the ROS 1 benchmark: nodes on ``kind: ros1`` targets, written as users write them.

They speak the rospy peer's protocol (``_rospy_peer``): a std_msgs/UInt8MultiArray whose
first 16 bytes are the sender's ``monotonic_ns`` stamp and a sequence number (-1 probes,
-2 stops). The echo node is a subscription callback that publishes the data back.
"""

from __future__ import annotations

import json
import struct
import time
from typing import Any

import numpy as np

from ..msg import registry
from ..runtime import Node

UInt8MultiArray = registry().get("std_msgs/msg/UInt8MultiArray")
PREFIX = struct.Struct("<qq")
PROBE = -1
STOP = -2


def ping(node: Node) -> None:
    size, warmup, reps = (int(node.get_parameter(k)) for k in ("size", "warmup", "reps"))
    gap = float(node.get_parameter("gap_s", 0.0))
    settle = float(node.get_parameter("settle_s", 0.0))
    publisher = node.create_publisher(UInt8MultiArray, "/bench_send")
    replies = node.create_subscription(UInt8MultiArray, "/bench_recv")
    buffer = np.zeros(PREFIX.size + size, np.uint8)

    def send(seq: int) -> None:
        PREFIX.pack_into(buffer, 0, time.monotonic_ns(), seq)  # type: ignore[arg-type]
        publisher.publish(UInt8MultiArray(data=buffer))

    deadline = time.monotonic() + 60
    while True:
        send(PROBE)
        try:
            replies.take(timeout=0.2)
            break
        except TimeoutError:
            if time.monotonic() > deadline:
                raise TimeoutError("the echo side never answered") from None
    while True:
        try:
            replies.take(timeout=0.1)
        except TimeoutError:
            break
    rtt = []
    for seq in range(warmup + reps):
        settled = time.monotonic() + settle
        while time.monotonic() < settled:  # awake: the echo finishes its reply, this CPU stays warm
            pass
        start = time.monotonic_ns()
        send(seq)
        while PREFIX.unpack_from(replies.take(timeout=10.0).data)[1] != seq:
            pass
        if seq >= warmup:
            rtt.append(time.monotonic_ns() - start)
        if gap:
            time.sleep(gap)
    send(STOP)
    time.sleep(0.2)
    with open(node.get_parameter("out"), "w") as out:
        json.dump({"rtt_ns": rtt}, out)


def echo(node: Node) -> None:
    warmup = int(node.get_parameter("warmup"))
    publisher = node.create_publisher(UInt8MultiArray, "/bench_recv")
    one_way: list[int] = []
    stopped = []

    def answer(message: Any) -> None:
        arrival = time.monotonic_ns()
        stamp, seq = PREFIX.unpack_from(message.data)
        if seq == STOP:
            stopped.append(seq)
            return
        if seq >= warmup:
            one_way.append(arrival - stamp)
        publisher.publish(UInt8MultiArray(data=message.data))

    subscription = node.create_subscription(UInt8MultiArray, "/bench_send", answer)
    while not stopped and node.ok():
        node.spin_once(0.5)
    subscription.close()
    with open(node.get_parameter("out"), "w") as out:
        json.dump({"one_way_ns": one_way}, out)
