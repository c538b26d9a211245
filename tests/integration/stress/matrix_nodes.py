"""Nodes of the reliability matrix, written as users write them.

The publisher publishes ``MESSAGES`` messages on every topic (at once or after a delay) and
returns: its process then ends once its subscribers have what it sent. Each subscriber
takes everything in one of the styles users write (callbacks with ``spin(t)`` loops,
``spin_once`` loops, ``spin()``, or a take-loop) and reports what arrived.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from hetros import Node
from hetros.interfaces.std_msgs.msg import Int32

MESSAGES = 10
PATIENCE = 60.0


def _names(node: Node) -> list[str]:
    pattern = str(node.get_parameter("names"))
    return [pattern.format(i=i) for i in range(int(node.get_parameter("topics")))]


def publisher(node: Node) -> None:
    pubs = [node.create_publisher(Int32, name) for name in _names(node)]
    delay = float(node.get_parameter("delay"))
    if delay:
        node.sleep(delay)
    for k in range(MESSAGES):
        for pub in pubs:
            pub.publish(Int32(data=k))


def subscriber(node: Node) -> None:
    names = _names(node)
    style = str(node.get_parameter("style"))
    received: dict[str, list[int]] = {name: [] for name in names}
    out = Path(node.get_parameter("out")) / f"{node.name}.json"
    wanted = MESSAGES * len(names)
    count = [0]

    def report() -> None:
        out.write_text(json.dumps(received))

    def on_message(name: str):  # type: ignore[no-untyped-def]
        def callback(message: Int32) -> None:
            received[name].append(int(message.data))
            count[0] += 1
            if style == "spin" and count[0] == wanted:
                report()  # spin() never returns before shutdown: the report is written here
        return callback

    if style == "take":
        subs = [node.create_subscription(Int32, name) for name in names]
        for name, sub in zip(names, subs, strict=True):
            for _ in range(MESSAGES):
                received[name].append(int(sub.take(timeout=PATIENCE).data))
        report()
        return
    for name in names:
        node.create_subscription(Int32, name, on_message(name))
    started = time.monotonic()
    if style == "spin":
        node.spin()
        return
    while count[0] < wanted and time.monotonic() - started < PATIENCE:
        if style == "spin_t":
            node.spin(0.05)
        else:
            node.spin_once(timeout=1.0)
    report()
