"""The shipped ROS 2 examples, run as a user would, with the independent peer as the ROS 2 side."""

from __future__ import annotations

import os
from pathlib import Path

from tests.support.ros2 import AddTwoIntsRequest, AddTwoIntsResponse, Peer, String, free_domain, launched, wait_for

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


def _env(domain: int) -> dict[str, str]:
    """ROS_DOMAIN_ID, as ROS 2 users select their domain."""
    return dict(os.environ, ROS_DOMAIN_ID=str(domain))


def test_talker_listener_over_ros2() -> None:
    domain = free_domain()
    with launched(EXAMPLES / "talker_listener" / "project_ros2.yaml", _env(domain)) as launch:
        peer = Peer(domain)
        echo = peer.reader("rt/chatter", String)  # what `ros2 topic echo /chatter` would subscribe
        heard: list[String] = []
        wait_for(lambda: heard.extend(echo.take(10)) or len(heard) >= 3, 30, "three of the talker's messages")
        assert all(m.data.startswith("hello world ") for m in heard)
        talker = peer.writer("rt/chatter", String)  # a stock ROS 2 talker
        wait_for(talker.get_matched_subscriptions, 20, "the bridge to match the ROS 2 talker")
        talker.write(String(data="hello from ROS 2"))
        lines: list[str] = []
        assert launch.stdout is not None
        for line in launch.stdout:
            lines.append(line)
            if "I heard: [hello from ROS 2]" in line:
                break
        assert any("I heard: [hello from ROS 2]" in line for line in lines), "".join(lines)


def test_add_two_ints_served_to_ros2() -> None:
    domain = free_domain()
    with launched(EXAMPLES / "add_two_ints" / "project_ros2.yaml", _env(domain)):
        peer = Peer(domain)
        requests = peer.writer("rq/add_two_intsRequest", AddTwoIntsRequest)
        replies = peer.reader("rr/add_two_intsReply", AddTwoIntsResponse)
        wait_for(lambda: requests.get_matched_subscriptions() and replies.get_matched_publications(), 30,
                 "/add_two_ints to be discovered")
        requests.write(AddTwoIntsRequest(client_guid=42, sequence_number=1, a=2, b=3))
        got: list[AddTwoIntsResponse] = []
        wait_for(lambda: got.extend(replies.take(1)) or got, 20, "the reply")
        assert (got[0].client_guid, got[0].sequence_number, got[0].sum) == (42, 1, 5)
