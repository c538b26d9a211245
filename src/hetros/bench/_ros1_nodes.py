"""hetros's side of the ROS 1 benchmark: nodes on ``kind: ros1`` targets, written as users write them.

They speak the rospy peer's protocol (``_rospy_peer``): a std_msgs/UInt8MultiArray whose
first 16 bytes are the sender's ``monotonic_ns`` stamp and a sequence number, the
sender's ``tag`` in its top bits (replies to tag t go to ``/bench_recv<t>``). The echo
node is a subscription callback that publishes the data back; it serves every tagged
sender at once, writing its one-way samples per tag at every STOP, until the launch is
stopped. A ping node given ``turns`` takes turns with another sender through two FIFOs,
a ``block`` of exchanges at a time (the first of each not measured).
"""

from __future__ import annotations

import json
import os
import struct
import time
from typing import Any

import numpy as np

from ..msg import registry
from ..runtime import Node

UInt8MultiArray = registry().get("std_msgs/msg/UInt8MultiArray")
PREFIX = struct.Struct("<qq")
TAG_SHIFT = 32
COUNT = (1 << TAG_SHIFT) - 1
PROBE = COUNT
STOP = COUNT - 1


def reply_topic(tag: int) -> str:
    return "/bench_recv" if tag == 0 else f"/bench_recv{tag}"


def measured(count: int, warmup: int, block: int) -> bool:
    """Whether exchange ``count`` is measured: past the warm-up, not the first of a block."""
    return count >= warmup and not (block and count % block == 0)


def _write(path: str, result: dict[str, Any]) -> None:
    """Replaced whole: the bench may read it while the echo rewrites it."""
    with open(path + ".part", "w") as out:
        json.dump(result, out)
    os.replace(path + ".part", path)


def _open_turns(turns: list[str] | None) -> tuple[int | None, int | None]:
    """The FIFOs this sender takes turns by (None, None when alone); says it is ready on the second."""
    if not turns:
        return None, None
    done = os.open(turns[1], os.O_WRONLY)
    os.write(done, b"r")
    return os.open(turns[0], os.O_RDONLY), done


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
    go, done = _open_turns(node.get_parameter("turns", None))
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
    _write(node.get_parameter("out"), {"rtt_ns": rtt})


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
            _write(out, {"one_way_ns": one_way})
            return
        if count != PROBE and measured(count, warmup, block):
            one_way.setdefault(str(sender), []).append(arrival - stamp)
        publishers[sender].publish(UInt8MultiArray(data=message.data))

    node.create_subscription(UInt8MultiArray, "/bench_send", answer)
    node.spin()
