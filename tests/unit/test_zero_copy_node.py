"""Zero copy through the node API: two processes' graphs of one session, in one test process."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import numpy as np
import pytest

from hetros import Node, ReadOnlyMessageError, TransportError
from hetros.interfaces.sensor_msgs.msg import Image
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


@pytest.mark.slow
def test_an_abandoned_loan_returns_its_slot(graphs: tuple[Graph, Graph]) -> None:
    """Loans live on their message: dropping one gives the slot back (no dict keeps it)."""
    import gc

    first, second = graphs
    second.prepare(["viewer"])
    pub = Node("cam", first).create_publisher(Image, "/img")
    for _ in range(50):
        abandoned = pub.loan(data=100_000)  # large: a slot loan (small ones live in process memory)
        del abandoned
        gc.collect(0)  # the young generation: a loan in a cycle would still be found, and it is quick
    message = pub.loan(data=100_000)
    message.data[:] = 9
    pub.publish(message)


def test_holding_too_many_loans_says_so(graphs: tuple[Graph, Graph]) -> None:
    first, _second = graphs  # no subscriber running: publishing never blocks here
    pub = Node("cam", first).create_publisher(Image, "/img")
    held = [pub.loan(data=100_000) for _ in range(8)]
    with pytest.raises(TransportError, match=r"holds at most 8 unpublished loans at once; publish the loaned"):
        pub.loan(data=100_000)
    for message in held:
        pub.publish(message)
    pub.publish(pub.loan(data=100_000))


def test_small_loans_live_in_process_memory_and_travel_inline(graphs: tuple[Graph, Graph]) -> None:
    """Below the inline limit a slot is not worth its bookkeeping: no slot is held per loan."""
    first, second = graphs
    second.prepare(["viewer"])
    viewer = Node("viewer", second)
    frames = viewer.create_subscription(Image, "/img")
    pub = Node("cam", first).create_publisher(Image, "/img")
    held = [pub.loan(data=3000) for _ in range(20)]  # more than a publisher's slot loans
    for value, message in enumerate(held):
        message.data[:] = value
        pub.publish(message)
        with pytest.raises(ValueError, match="read-only"):
            message.data[0] = 1  # handed over
        assert frames.take(timeout=2.0).data[0] == value


def test_a_slot_loan_read_in_this_process_too_reaches_both_readers_whole(shm_session: str) -> None:
    """The shared-memory writer lends the slot; an in-process reader of the same publisher gets
    its own frozen copy, since the slot leaves with the shared-memory send."""
    plan = Plan(
        "zc", "/", (),
        {"p1": TargetPlan("p1", "process"), "p2": TargetPlan("p2", "process")},
        {"cam": NodePlan("cam", "m:f", "p1", publish={"/img": "sensor_msgs/msg/Image"}),
         "local": NodePlan("local", "m:f", "p1", subscribe={"/img": "sensor_msgs/msg/Image"}),
         "viewer": NodePlan("viewer", "m:f", "p2", subscribe={"/img": "sensor_msgs/msg/Image"})},
        {"/img": ChannelPlan("/img", "sensor_msgs/msg/Image", "topic", QoS(depth=3), ("cam",),
                             ("local", "viewer"))},
        (EdgePlan("/img", "cam", "local", "inproc"), EdgePlan("/img", "cam", "viewer", "shm")),
    )
    first, second = Graph(plan, "p1", shm_session), Graph(plan, "p2", shm_session)
    try:
        remote = Node("viewer", second).create_subscription(Image, "/img")
        local = Node("local", first).create_subscription(Image, "/img")
        pub = Node("cam", first).create_publisher(Image, "/img")
        frame = pub.loan(data=300_000)
        assert in_shared_memory(frame.data)
        frame.data[:] = 9
        pub.publish(frame)
        there, here = remote.take(timeout=5), local.take(timeout=5)
        assert in_shared_memory(there.data) and not in_shared_memory(here.data)
        assert int(there.data.sum()) == int(here.data.sum()) == 9 * 300_000
        assert not here.data.flags.writeable and not there.data.flags.writeable
    finally:
        second.close()
        first.close()
        remove_session_segments(shm_session)
