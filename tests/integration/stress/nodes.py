"""Nodes of the reliability stress test: one publisher and one subscriber of many topics."""

from __future__ import annotations

import json
import os
import resource
import threading
from pathlib import Path

from hetros import Node
from hetros.interfaces.std_msgs.msg import Int32

MESSAGES = 10


def _resources() -> dict[str, int]:
    return {"fds": len(os.listdir("/proc/self/fd")), "threads": threading.active_count(),
            "soft_limit": resource.getrlimit(resource.RLIMIT_NOFILE)[0]}


def _report(node: Node, role: str, extra: dict[str, object]) -> None:
    out = Path(node.get_parameter("out"))
    (out / f"{role}.json").write_text(json.dumps({**_resources(), **extra}))


def publisher(node: Node) -> None:
    topics = int(node.get_parameter("topics"))
    pubs = [node.create_publisher(Int32, f"/t{i}") for i in range(topics)]
    for k in range(MESSAGES):
        for pub in pubs:
            pub.publish(Int32(data=k))
    _report(node, "publisher", {})
    node.sleep(60.0)


def subscriber(node: Node) -> None:
    topics = int(node.get_parameter("topics"))
    received: list[list[int]] = [[] for _ in range(topics)]
    complete = threading.Event()
    remaining = [topics]

    def on_message(index: int):  # type: ignore[no-untyped-def]
        def callback(message: Int32) -> None:
            received[index].append(int(message.data))
            if len(received[index]) == MESSAGES:
                remaining[0] -= 1
                if not remaining[0]:
                    complete.set()
        return callback

    for i in range(topics):
        node.create_subscription(Int32, f"/t{i}", on_message(i))
    if node.get_parameter("squeeze", False):
        # leave too few descriptors for the connections to the publisher: iceoryx2 then
        # cannot receive, and hetros must say so instead of losing the topics silently
        resource.setrlimit(resource.RLIMIT_NOFILE, (len(os.listdir("/proc/self/fd")) + 5,
                                                    resource.getrlimit(resource.RLIMIT_NOFILE)[1]))
    while not complete.is_set() and node.ok():
        if not node.spin_once(timeout=float(node.get_parameter("patience"))):
            break
    complete_topics = sum(r == list(range(MESSAGES)) for r in received)
    _report(node, "subscriber", {"complete": complete_topics, "topics": topics})
