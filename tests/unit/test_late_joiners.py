"""A subscription made after its node began to spin is a late joiner, as in ROS 2
(``hetros.runtime._endpoints.RetainedReader``): the reader kept for it from start-up stops holding
publishers back once the node spins, and hands the subscription what its durability and lifespan
allow; in one process each publisher's messages expire by its own lifespan (``InprocWriter``)."""

from __future__ import annotations

import time

import pytest

from hetros import QoS
from hetros.runtime._endpoints import Relay, RetainedReader
from hetros.transport._inproc import InprocTopic

RELIABLE = QoS(depth=3)  # reliable keep_all: a full FIFO makes the publisher wait


def _retained(topic: InprocTopic) -> tuple[RetainedReader, list[str]]:
    relay = Relay()
    woken: list[str] = []
    relay.target = lambda: woken.append("woken")
    return RetainedReader(topic.open_reader("late", relay), relay, lambda reader: None), woken


def test_an_unclaimed_reader_holds_the_publisher_back_only_until_its_node_spins() -> None:
    topic = InprocTopic("/t", RELIABLE)
    reader, _ = _retained(topic)
    for seq in range(3):
        topic.deliver(seq)
    assert not topic.has_room()  # start-up: the FIFO keeps what the node has not subscribed to yet
    reader.lapse(RELIABLE.depth)
    assert topic.has_room()
    for seq in range(3, 10):
        topic.deliver(seq)  # would wait, then raise PublishTimeoutError, were the reader still holding
    assert topic.has_room()
    reader.join_late(QoS(depth=3, durability="transient_local"))
    assert [reader.try_take() for _ in range(4)] == [7, 8, 9, None]


@pytest.mark.parametrize(("durability", "heard"), [("volatile", []), ("transient_local", [1, 2])])
def test_a_late_joiner_gets_what_its_durability_asks(durability: str, heard: list[int]) -> None:
    topic = InprocTopic("/t", RELIABLE)
    reader, _ = _retained(topic)
    for seq in range(3):
        topic.deliver(seq)
    reader.join_late(QoS(depth=2, durability=durability))  # type: ignore[arg-type]
    assert [reader.try_take() for _ in range(len(heard))] == heard
    topic.deliver(3)  # what comes after joining arrives in any case
    assert [reader.try_take(), reader.try_take()] == [3, None]
    assert reader.taker()() is None


def test_a_late_joiner_gets_nothing_older_than_the_lifespan() -> None:
    topic = InprocTopic("/t", RELIABLE)
    reader, _ = _retained(topic)
    reader.lapse(RELIABLE.depth)
    topic.deliver("old")
    time.sleep(0.3)
    topic.deliver("young")
    reader.join_late(QoS(depth=3, durability="transient_local", lifespan=0.2))
    assert [reader.try_take(), reader.try_take()] == ["young", None]


def test_the_taker_of_a_late_joiner_hands_its_backlog_first() -> None:
    topic = InprocTopic("/t", RELIABLE)
    reader, _ = _retained(topic)
    topic.deliver(0)
    reader.join_late(QoS(depth=3, durability="transient_local"))
    take = reader.taker()
    topic.deliver(1)
    assert [take(), take(), take()] == [0, 1, None]
    assert not reader.pending()


def test_each_publisher_in_a_process_expires_its_messages_by_its_own_lifespan() -> None:
    topic = InprocTopic("/t", QoS(depth=10, durability="transient_local"))
    short, lasting = topic.open_writer(lifespan=0.1), topic.open_writer()
    early = topic.open_reader("early", lambda: None)
    short.write("short")
    lasting.write("lasting")
    time.sleep(0.2)
    assert [early.try_take(), early.try_take()] == ["lasting", None]
    assert early.expired == 1
    # the history a late reader gets expires as it would have for an early one
    late = topic.open_reader("late", lambda: None)
    assert [late.try_take(), late.try_take()] == ["lasting", None]
