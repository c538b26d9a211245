"""Services both ways with a peer that speaks rmw_cyclonedds's request header itself, and what
ROS 2's tools would read about hetros: ``ros_discovery_info`` and each endpoint's type hash."""

from __future__ import annotations

import subprocess
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

from hetros.msg import registry
from tests.support.ros2 import (
    AddTwoIntsRequest,
    AddTwoIntsResponse,
    ParticipantEntitiesInfo,
    Peer,
    String,
    free_domain,
    latched_qos,
    launched,
    wait_for,
    write_project,
)

NODES = textwrap.dedent('''
    import time
    from hetros.interfaces.example_interfaces.srv import AddTwoInts
    from hetros.interfaces.std_msgs.msg import String

    def server(node):
        node.create_service(AddTwoInts, "/add_two_ints", lambda r: AddTwoInts.Response(sum=r.a + r.b))
        node.spin()

    def talker(node):
        pub = node.create_publisher(String, "/chatter")
        while not node.graph.stop.is_set():
            pub.publish(String(data="hi"))
            time.sleep(0.1)

    def caller(node):
        client = node.create_client(AddTwoInts, "/ros2_add")
        with open(node.get_parameter("out"), "a") as out:
            for a in range(3):
                response = client.call(AddTwoInts.Request(a=a, b=100), timeout=20)
                out.write(f"{a}+100={response.sum}\\n")
                out.flush()
        node.spin()
''')


@pytest.fixture
def graph(tmp_path: Path) -> Iterator[tuple[int, Path, subprocess.Popen[str]]]:
    domain = free_domain()
    project = write_project(tmp_path, NODES, f"""
        name: ros2_services
        targets: {{main: {{kind: thread}}, worker: {{kind: process}}}}
        nodes:
          server: {{run: nodes:server, target: worker,
                   services: {{/add_two_ints: example_interfaces/srv/AddTwoInts}}}}
          talker: {{run: nodes:talker, target: main, publish: {{/chatter: std_msgs/msg/String}}}}
          caller: {{run: nodes:caller, target: worker, parameters: {{out: {tmp_path / "got.txt"}}},
                   clients: {{/ros2_add: example_interfaces/srv/AddTwoInts}}}}
        external:
          ros2: {{domain: {domain}, export: [/chatter], export_services: [/add_two_ints],
                 import_services: [/ros2_add]}}
    """)
    with launched(project) as launch:
        yield domain, tmp_path / "got.txt", launch


def test_a_ros2_client_calls_a_hetros_service(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    domain, _got, launch = graph
    peer = Peer(domain)
    requests = peer.writer("rq/add_two_intsRequest", AddTwoIntsRequest)
    replies = peer.reader("rr/add_two_intsReply", AddTwoIntsResponse)
    wait_for(lambda: requests.get_matched_subscriptions() and replies.get_matched_publications(), 20,
             "the hetros service to be discovered")
    guid = 0x1122334455667788
    for sequence, (a, b) in enumerate([(2, 3), (-7, 1 << 40), (0, 0)], start=1):
        requests.write(AddTwoIntsRequest(client_guid=guid, sequence_number=sequence, a=a, b=b))
    answers: list[AddTwoIntsResponse] = []
    wait_for(lambda: answers.extend(replies.take(10)) or len(answers) >= 3, 20, "three replies")
    assert sorted((r.client_guid, r.sequence_number, r.sum) for r in answers) == [
        (guid, 1, 5), (guid, 2, (1 << 40) - 7), (guid, 3, 0)]
    assert launch.poll() is None


def test_a_hetros_client_calls_a_ros2_service(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    domain, got, launch = graph
    peer = Peer(domain)
    requests = peer.reader("rq/ros2_addRequest", AddTwoIntsRequest)
    replies = peer.writer("rr/ros2_addReply", AddTwoIntsResponse)
    answered = 0

    def serve() -> bool:
        nonlocal answered
        for request in requests.take(10):
            replies.write(AddTwoIntsResponse(client_guid=request.client_guid,
                                             sequence_number=request.sequence_number, sum=request.a + request.b))
            answered += 1
        return got.exists() and len(got.read_text().splitlines()) == 3

    wait_for(serve, 30, "the hetros client's three calls answered")
    assert got.read_text().splitlines() == ["0+100=100", "1+100=101", "2+100=102"]
    assert answered == 3
    assert launch.poll() is None


def test_ros2_tools_learn_hetros_nodes_and_type_hashes(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    """What `ros2 node list` / `ros2 topic info -v` read: ros_discovery_info and USER_DATA."""
    domain, _got, _launch = graph
    peer = Peer(domain)
    info = peer.reader("ros_discovery_info", ParticipantEntitiesInfo, qos=latched_qos())
    chatter = peer.reader("rt/chatter", String)
    entries: list[ParticipantEntitiesInfo] = []
    wait_for(lambda: entries.extend(info.take(10)) or entries, 20, "a ros_discovery_info sample")
    wait_for(lambda: chatter.get_matched_publications(), 20, "rt/chatter's writer")
    nodes = {n.node_name: n for n in entries[-1].node_entities_info_seq}
    assert set(nodes) == {"talker", "server", "caller"}  # the hetros nodes that own what crosses
    assert all(n.node_namespace == "/" for n in nodes.values())
    [writer] = chatter.get_matched_publications()
    endpoint = chatter.get_matched_publication_data(writer)
    assert bytes(endpoint.key.bytes) in {bytes(g.data) for g in nodes["talker"].writer_gid_seq}
    assert endpoint.type_name == "std_msgs::msg::dds_::String_"
    expected = registry().store.hash_rihs01("std_msgs/msg/String")
    user_data = [p for p in endpoint.qos if type(p).__name__ == "Userdata"]
    assert user_data and user_data[0].data == f"typehash={expected};".encode()
    for name in ("server", "caller"):  # a service is a request reader and a reply writer, a client the reverse
        assert len(nodes[name].reader_gid_seq) == 1 and len(nodes[name].writer_gid_seq) == 1
