"""Zero copy through the node API: two processes' graphs of one session, in one test process."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import numpy as np
import pytest
from hetros.interfaces.sensor_msgs.msg import Image

from hetros import Node, ReadOnlyMessageError
from hetros.plan import ChannelPlan, EdgePlan, NodePlan, Plan, TargetPlan
from hetros.runtime import Graph
from hetros.transport import QoS, remove_session_segments

from ..conformance.test_shm_specific import in_shared_memory


@pytest.fixture
def graphs(shm_session: str) -> Iterator[tuple[Graph, Graph]]:
    plan = Plan(
        "zc", "/", (),
        {"p1": TargetPlan("p1", "process"), "p2": TargetPlan("p2", "process")},
        {"cam": NodePlan("cam", "m:f", "p1", publish={"/img": "sensor_msgs/msg/Image"}),
         "viewer": NodePlan("viewer", "m:f", "p2", subscribe={"/img": "sensor_msgs/msg/Image"})},
        {"/img": ChannelPlan("/img", "sensor_msgs/msg/Image", "topic", QoS(depth=3), ("cam",), ("viewer",))},
        (EdgePlan("/img", "cam", "viewer", "shm"),),
    )
    first, second = Graph(plan, "p1", shm_session), Graph(plan, "p2", shm_session)
    yield first, second
    second.close()
    first.close()
    remove_session_segments(shm_session)


def test_loaned_image_arrives_as_a_shared_memory_view(graphs: tuple[Graph, Graph]) -> None:
    sub = Node("viewer", graphs[1]).create_subscription(Image, "/img")
    pub = Node("cam", graphs[0]).create_publisher(Image, "/img")
    frame = pub.loan(data=640 * 480 * 3)
    assert in_shared_memory(frame.data)
    frame.height, frame.width, frame.step, frame.encoding = 480, 640, 1920, "rgb8"
    frame.data[:] = np.arange(frame.data.size, dtype=np.uint64).astype(np.uint8)
    pub.publish(frame)
    got = sub.take(timeout=5)
    assert (got.height, got.width, got.encoding) == (480, 640, "rgb8")
    assert np.array_equal(got.data, np.arange(640 * 480 * 3, dtype=np.uint64).astype(np.uint8))
    assert in_shared_memory(got.data) and not got.data.flags.writeable
    with pytest.raises(ReadOnlyMessageError):
        got.width = 1


def test_plain_publish_and_callback_delivery(graphs: tuple[Graph, Graph]) -> None:
    viewer = Node("viewer", graphs[1])
    seen: list[tuple[int, bool]] = []
    done = threading.Event()

    def on_image(msg: Image) -> None:
        seen.append((int(msg.data.sum()), in_shared_memory(msg.data)))
        if len(seen) == 3:
            done.set()

    viewer.create_subscription(Image, "/img", on_image)
    spinner = threading.Thread(target=viewer.spin, daemon=True)
    spinner.start()
    pub = Node("cam", graphs[0]).create_publisher(Image, "/img")
    for value in (1, 2, 3):
        pub.publish(Image(data=np.full(1000, value, dtype=np.uint8)))
    assert done.wait(5)
    graphs[1].shutdown()
    spinner.join(2)
    assert seen == [(1000, True), (2000, True), (3000, True)]
