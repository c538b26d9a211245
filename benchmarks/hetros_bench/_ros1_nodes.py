"""hetros's side of the ROS 1 benchmark: nodes on ``kind: ros1`` targets, written as users write them.

They speak the protocol of ``_ros1_protocol``, as the rospy peer does. The echo node is a
subscription callback that publishes the data back; it serves every tagged sender at
once, writing its one-way samples per tag at every STOP, until the launch is stopped. A
ping node given ``turns`` takes turns with another sender, a ``block`` of exchanges at a
time.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np

from hetros.msg import registry
from hetros.runtime import Node

from ._ros1_protocol import COUNT, PREFIX, PROBE, STOP, TAG_SHIFT, measured, open_turns, reply_topic, write_result

UInt8MultiArray = registry().get("std_msgs/msg/UInt8MultiArray")


def ping(node: Node) -> None:
    size, warmup, reps = (int(node.get_parameter(k)) for k in ("size", "warmup", "reps"))
    gap = float(node.get_parameter("gap_s", 0.0))
    settle = float(node.get_parameter("settle_s", 0.0))
    tag = int(node.get_parameter("tag", 0))
    block = int(node.get_parameter("block", 0))
    top = tag << TAG_SHIFT
    publisher = node.create_publisher(UInt8MultiArray, "/bench_send")
    replies = node.create_subscription(UInt8MultiArray, reply_topic(tag))
    buffer = np.zeros(PREFIX.size + size, np.uint8)

    def send(count: int) -> int:
        stamp = time.monotonic_ns()
        PREFIX.pack_into(buffer, 0, stamp, top | count)  # type: ignore[arg-type]
        publisher.publish(UInt8MultiArray(data=buffer))
        return stamp

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
    go, done = open_turns(node.get_parameter("turns", None))
    rtt = []
    total, turn = warmup + reps, block or 1
    for count in range(total):
        if go is not None and count % turn == 0:
            os.read(go, 1)
        settled = time.monotonic() + settle
        while time.monotonic() < settled:  # awake: the echo finishes its reply, this CPU stays warm
            pass
        start = send(count)
        while PREFIX.unpack_from(replies.take(timeout=10.0).data)[1] != top | count:
            pass
        if measured(count, warmup, block):
            rtt.append(time.monotonic_ns() - start)
        if done is not None and (count % turn == turn - 1 or count == total - 1):
            os.write(done, b"d")
        if gap:
            time.sleep(gap)
    send(STOP)
    time.sleep(0.2)
    write_result(node.get_parameter("out"), {"rtt_ns": rtt})


def echo(node: Node) -> None:
    warmup = int(node.get_parameter("warmup"))
    block = int(node.get_parameter("block", 0))
    out = node.get_parameter("out")
    publishers = {tag: node.create_publisher(UInt8MultiArray, reply_topic(tag))
                  for tag in node.get_parameter("tags", [0])}
    one_way: dict[str, list[int]] = {}

    def answer(message: Any) -> None:
        arrival = time.monotonic_ns()
        stamp, seq = PREFIX.unpack_from(message.data)
        sender, count = seq >> TAG_SHIFT, seq & COUNT
        if count == STOP:
            write_result(out, {"one_way_ns": one_way})
            return
        if count != PROBE and measured(count, warmup, block):
            one_way.setdefault(str(sender), []).append(arrival - stamp)
        publishers[sender].publish(UInt8MultiArray(data=message.data))

    node.create_subscription(UInt8MultiArray, "/bench_send", answer)
    node.spin()
