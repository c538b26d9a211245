"""A ROS 1 node's slave API under announcements it cannot trust: bounded threads, typed lists,
limited log lines. Real sockets on loopback, an in-process `hetros master`."""

from __future__ import annotations

import logging
import threading
import time
import xmlrpc.client
from collections.abc import Iterator

import pytest

from hetros._log import BURST
from hetros.msg import registry
from hetros.transport.tcpros import Master, Ros1Peer, Ros1Type
from hetros.transport.tcpros._peer import MAX_CONNECTORS


@pytest.fixture
def peer() -> Iterator[Ros1Peer]:
    master = Master(port=0)
    node = Ros1Peer("/limits", master.uri)
    node.subscribe("/x", Ros1Type(registry(), "std_msgs/msg/String"), lambda message: None)
    yield node
    node.close()
    master.close()


def test_a_thousand_dead_publishers_cost_a_few_threads_and_twenty_lines(peer: Ros1Peer,
                                                                      caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING)
    before = threading.active_count()
    slave = xmlrpc.client.ServerProxy(peer.uri)
    dead = [f"http://127.0.0.1:1/dead{n}" for n in range(1000)]
    assert slave.publisherUpdate("/master", "/x", dead)[0] == 1
    most = 0
    deadline = time.monotonic() + 30
    while (peer._to_connect or peer._connectors) and time.monotonic() < deadline:
        most = max(most, threading.active_count() - before)
        time.sleep(0.005)
    assert not peer._to_connect, "the dead publishers were not all tried"
    assert most <= MAX_CONNECTORS + 2, f"{most} threads for 1,000 dead publishers"
    refused = [r for r in caplog.records if "cannot reach the ROS 1 publisher" in r.getMessage()]
    assert len(refused) <= BURST, f"{len(refused)} warnings for one repeated problem"


def test_a_publisher_list_that_is_not_strings_is_refused_with_roses_error_code(peer: Ros1Peer) -> None:
    code, message, _ = xmlrpc.client.ServerProxy(peer.uri).publisherUpdate("/master", "/x", [1, 2, 3])
    assert code == -1 and "must be a list of strings" in message
