"""The ROS 2 wire: names, bytes (hand-annotated and against rosbags), QoS, configuration, and
what `hetros check` says about `external: ros2:`. One process; the interop suite runs peers."""

from __future__ import annotations

import random
import textwrap
import time
from pathlib import Path

import pytest
from cyclonedds._clayer import ddspy_write
from cyclonedds.core import Policy
from rosbags.typesys import Stores, get_typestore

from hetros import SerializationError, TransportError
from hetros.msg import registry
from hetros.project import check, load_project, plan
from hetros.project._graph import describe
from hetros.transport import QoS
from hetros.transport.dds import (
    DdsDomain,
    DdsServiceClient,
    DdsServiceServer,
    DdsTopicReader,
    DdsTopicWriter,
    config_xml,
    dds_qos,
    dds_type_name,
    default_domain_id,
    idl_type,
    reply_topic,
    request_topic,
    topic_name,
)
from hetros.transport.dds._endpoints import _RequestCodec
from tests.support.messages import random_message
from tests.support.ros2 import Peer, String, free_domain, raw_samples, wait_for

TYPES = registry()
JAZZY = get_typestore(Stores.ROS2_JAZZY)


def test_names_are_rmw_cyclonedds_s() -> None:
    assert topic_name("/chatter") == "rt/chatter"
    assert topic_name("/robot1/scan") == "rt/robot1/scan"
    assert request_topic("/add_two_ints") == "rq/add_two_intsRequest"
    assert reply_topic("/add_two_ints") == "rr/add_two_intsReply"
    assert dds_type_name("std_msgs/msg/String") == "std_msgs::msg::dds_::String_"
    assert dds_type_name("example_interfaces/srv/AddTwoInts_Request") == \
        "example_interfaces::srv::dds_::AddTwoInts_Request_"
    with pytest.raises(TransportError, match="absolute like '/chatter', not 'chatter'"):
        topic_name("chatter")
    with pytest.raises(TransportError, match="'package/kind/Name', not 'String'"):
        dds_type_name("String")


def test_the_announced_type_names_and_shapes_are_ros2_s() -> None:
    string = idl_type(TYPES, "std_msgs/msg/String")
    assert string.__idl_typename__ == "std_msgs::msg::dds_::String_"
    image = idl_type(TYPES, "sensor_msgs/msg/Image")
    assert list(image.__annotations__) == ["header", "height", "width", "encoding", "is_bigendian", "step", "data"]
    request = idl_type(TYPES, "example_interfaces/srv/AddTwoInts_Request", True)
    assert request.__idl_typename__ == "example_interfaces::srv::dds_::AddTwoInts_Request_"
    assert list(request.__annotations__) == ["client_guid", "sequence_number", "a", "b"]


def test_a_request_is_the_header_then_the_body_hand_annotated() -> None:
    codec = _RequestCodec(TYPES, "example_interfaces/srv/AddTwoInts_Request", "/add_two_ints")
    request = TYPES.get("example_interfaces/srv/AddTwoInts_Request")(a=2, b=-3)
    data = codec.encode(0x1122334455667788, 7, request)
    assert bytes(data) == bytes.fromhex(
        "00 01 00 00"                # XCDR1, little endian, no options
        "88 77 66 55 44 33 22 11"    # client id (rmw_cyclonedds: the request writer's instance handle)
        "07 00 00 00 00 00 00 00"    # sequence number
        "02 00 00 00 00 00 00 00"    # a = 2
        "fd ff ff ff ff ff ff ff"    # b = -3
    )
    client, sequence, decoded = codec.decode(bytes(data))
    assert (client, sequence, decoded.a, decoded.b) == (0x1122334455667788, 7, 2, -3)
    with pytest.raises(SerializationError, match=r"/add_two_ints .* not little-endian XCDR1.*start 00 00 00 00"):
        codec.decode(b"\x00\x00\x00\x00" + bytes(data[4:]))
    with pytest.raises(SerializationError, match="10 bytes are not"):
        codec.decode(bytes(data[:10]))


def test_qos_maps_one_to_one_and_always_xcdr1() -> None:
    policies = list(dds_qos(QoS(reliability="reliable", history="keep_last", depth=5,
                                durability="transient_local", publish_timeout=2.0), b"typehash=x;"))
    assert Policy.Reliability.Reliable(max_blocking_time=0) in policies  # the wait is hetros's (GIL)
    assert Policy.History.KeepLast(5) in policies
    assert Policy.Durability.TransientLocal in policies
    assert Policy.DataRepresentation(use_cdrv0_representation=True) in policies
    assert Policy.Userdata(data=b"typehash=x;") in policies
    best = list(dds_qos(QoS(reliability="best_effort", history="keep_all")))
    assert Policy.Reliability.BestEffort in best and Policy.History.KeepAll in best
    assert Policy.Durability.Volatile in best
    timed = list(dds_qos(QoS(deadline=0.1, lifespan=2.0, liveliness="manual_by_topic", lease_duration=0.5)))
    assert Policy.Deadline(100_000_000) in timed and Policy.Lifespan(2_000_000_000) in timed
    assert Policy.Liveliness.ManualByTopic(500_000_000) in timed
    assert not any(isinstance(p, Policy.Deadline | Policy.Lifespan) for p in best), "none: DDS's infinite"


def test_discovery_is_static_and_on_loopback_by_default(monkeypatch: pytest.MonkeyPatch) -> None:
    xml = config_xml("127.0.0.1", ["127.0.0.1"], multicast=False)
    assert '<NetworkInterface address="127.0.0.1"/>' in xml
    assert "<AllowMulticast>false</AllowMulticast>" in xml
    assert '<Peer address="127.0.0.1"/>' in xml
    monkeypatch.delenv("ROS_DOMAIN_ID", raising=False)
    assert default_domain_id() == 0
    monkeypatch.setenv("ROS_DOMAIN_ID", "42")
    assert default_domain_id() == 42
    monkeypatch.setenv("ROS_DOMAIN_ID", "300")
    with pytest.raises(TransportError, match="ROS_DOMAIN_ID must be a number from 0 to 232, not '300'"):
        default_domain_id()


@pytest.fixture(scope="module")
def domain() -> DdsDomain:
    return DdsDomain(free_domain())


@pytest.mark.parametrize("typename", ["std_msgs/msg/String", "sensor_msgs/msg/Image", "geometry_msgs/msg/PoseStamped",
                                      "sensor_msgs/msg/PointCloud2", "std_msgs/msg/Float64MultiArray"])
def test_the_bytes_on_the_wire_are_rosbags_bytes(domain: DdsDomain, typename: str) -> None:
    """Random messages through a hetros writer arrive at an independent reader as rosbags' CDR."""
    peer = Peer(domain.domain_id)
    topic = f"/wire_{typename.replace('/', '_')}"
    writer = DdsTopicWriter(domain, TYPES, topic, typename, QoS())
    reader = peer.reader(topic_name(topic), idl_type(TYPES, typename))
    wait_for(writer.matched, 10, "the peer's reader")
    rnd = random.Random(typename)
    sent = [random_message(TYPES, typename, rnd) for _ in range(5)]
    for message in sent:
        writer.write(message)
    got: list[bytes] = []
    wait_for(lambda: got.extend(raw_samples(reader)) or len(got) == len(sent), 10, "five samples")
    for message, data in zip(sent, got, strict=True):
        reference = bytes(JAZZY.serialize_cdr(_to_rosbags(message, typename), typename))
        assert data[:len(reference)] == reference
        assert len(data) == (len(reference) + 3) & ~3 and not any(data[len(reference):])


def _to_rosbags(message: object, typename: str) -> object:
    """The same message as rosbags' class (through its own deserializer of hetros's reference codec)."""
    from hetros.msg._cdr import reference_codec

    codec = reference_codec(TYPES, typename)
    buffer = bytearray(codec.size(message))
    codec.encode(message, memoryview(buffer))
    return JAZZY.deserialize_cdr(b"\x00\x01\x00\x00" + bytes(buffer), typename)


def test_a_reader_skips_its_own_samples_and_takes_a_big_endian_peers(domain: DdsDomain) -> None:
    """A topic both exported and imported is not echoed back; Cyclone validates and byte-swaps
    what arrives (malformed CDR is refused before it reaches hetros), so a big-endian peer works."""
    got: list[str] = []
    reader = DdsTopicReader(domain, TYPES, "/mixed", "std_msgs/msg/String", QoS(), lambda m: got.append(m.data))
    own = DdsTopicWriter(domain, TYPES, "/mixed", "std_msgs/msg/String", QoS())
    peer = Peer(domain.domain_id)
    writer = peer.writer("rt/mixed", String)
    wait_for(lambda: reader.matched() >= 2, 10, "both writers")
    own.write(TYPES.get("std_msgs/msg/String")(data="mine"))
    assert ddspy_write(writer._ref, b"\x00\x00\x00\x00" b"\x00\x00\x00\x04" b"abc\x00") == 0  # CDR_BE "abc"
    writer.write(String(data="after"))
    wait_for(lambda: got == ["abc", "after"], 10, f"the peer's two samples, not {got}")
    time.sleep(0.1)
    assert got == ["abc", "after"]
    assert reader.received == 2


def test_a_service_round_trip_in_one_domain(domain: DdsDomain) -> None:
    response_type = TYPES.get("example_interfaces/srv/AddTwoInts_Response")
    server = DdsServiceServer(domain, TYPES, "/unit_add", "example_interfaces/srv/AddTwoInts",
                              lambda request, respond: respond(response_type(sum=request.a + request.b)))
    client = DdsServiceClient(domain, TYPES, "/unit_add", "example_interfaces/srv/AddTwoInts")
    wait_for(client.ready, 10, "the server")
    request = TYPES.get("example_interfaces/srv/AddTwoInts_Request")
    futures = [client.call_async(request(a=i, b=i)) for i in range(10)]
    assert [f.result(5).sum for f in futures] == [2 * i for i in range(10)]
    del server  # an endpoint nobody holds is deleted at once (its listener holds it weakly)
    assert wait_for(lambda: not client.ready(), 10, "the server's endpoints to go")


NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String

    def talker(node):
        node.create_publisher(String, "/chatter")

    def listener(node):
        node.create_subscription(String, "/chatter", print)
''')


def _project(tmp_path: Path, external: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text(textwrap.dedent("""
        name: ros2_check
        nodes:
          talker: {run: nodes:talker, target: main, publish: {/chatter: std_msgs/msg/String}}
          listener: {run: nodes:listener, target: main, subscribe: {/chatter: std_msgs/msg/String}}
        external:
    """) + textwrap.indent(external, "  ") + "\n")
    return path


@pytest.mark.parametrize(("external", "expected"), [
    ("ros2: {export: [/nothing]}", r"external\.ros2\.export\.0.*/nothing has no hetros publisher to export"),
    ("ros2: {import: [/nothing]}", r"external\.ros2\.import\.0.*/nothing has no hetros subscriber to import"),
    ("ros2: {export_services: [/none]}", r"external\.ros2\.export_services\.0.*/none has no hetros server"),
    ("ros2: {import_actions: [/none]}", r"external\.ros2\.import_actions\.0.*/none has no hetros action client"),
    ("ros2: {domain: 300}", r"external\.ros2\.domain.*less than or equal to 232"),
    ("ros2: {exports: [/chatter]}", r"external\.ros2\.exports: unknown key .exports."),
])
def test_bad_ros2_sections_are_refused_by_check(tmp_path: Path, external: str, expected: str) -> None:
    with pytest.raises(Exception, match=expected):
        plan(load_project(_project(tmp_path, external)))


def test_an_imported_topic_needs_no_hetros_publisher_and_the_graph_names_the_dds_side(tmp_path: Path) -> None:
    path = _project(tmp_path, "ros2: {domain: 5, export: [/chatter], import: [/from_ros2]}")
    both = "subscribe: {/chatter: std_msgs/msg/String, /from_ros2: std_msgs/msg/String}"
    path.write_text(path.read_text().replace("subscribe: {/chatter: std_msgs/msg/String}", both))
    built = plan(load_project(path))
    bridge = built.nodes["hetros_ros2_bridge"]
    assert bridge.subscribe == {"/chatter": "std_msgs/msg/String"}
    assert bridge.publish == {"/from_ros2": "std_msgs/msg/String"}
    assert bridge.parameters["owners"] == {"export": {"/chatter": ["talker"]}, "import": {"/from_ros2": ["listener"]},
                                           "export_services": {}, "import_services": {}}
    text = describe(built)
    assert "/chatter [std_msgs/msg/String] exported to ROS 2 as rt/chatter  via dds (ROS 2 domain 5" in text
    assert "/from_ros2 [std_msgs/msg/String] imported from ROS 2 as rt/from_ros2" in text
    without = _project(tmp_path, "ros2: {export: [/chatter]}")
    without.write_text(without.read_text().replace("subscribe: {/chatter: std_msgs/msg/String}",
                                                   "subscribe: {/from_ros2: std_msgs/msg/String}"))
    report = check(load_project(without))  # ROS lets a subscriber wait: a warning that names the import
    assert not any("publishes /from_ros2" in e for e in report.errors), report.errors
    assert any("nobody in the project publishes /from_ros2" in w and "import the topic (external: ros1: / ros2: "
               "import:)" in w for w in report.warnings), report.warnings


def test_cyclone_listens_only_on_the_named_interface(domain: DdsDomain) -> None:
    """Cyclone binds its receive sockets to 0.0.0.0; hetros pins them to the interface's device."""
    import os
    import socket
    import stat

    first = 7400 + 250 * domain.domain_id
    devices = {}
    for entry in os.listdir("/proc/self/fd"):
        try:
            if not stat.S_ISSOCK(os.fstat(int(entry)).st_mode):
                continue
            sock = socket.socket(fileno=os.dup(int(entry)))
        except OSError:
            continue
        with sock:
            if sock.family == socket.AF_INET and sock.type == socket.SOCK_DGRAM:
                host, port = sock.getsockname()
                if host == "0.0.0.0" and first <= port < first + 250:
                    devices[port] = sock.getsockopt(socket.SOL_SOCKET, socket.SO_BINDTODEVICE, 16).rstrip(b"\0")
    assert devices and set(devices.values()) == {b"lo"}, devices
    with pytest.raises(TransportError, match=r"cannot join DDS domain \d+ on 10.255.255.1: .*10.255.255.1 must be an "
                                             r"address of this machine: check external.ros2.interface"):
        DdsDomain(free_domain(), interface="10.255.255.1")


def test_a_domain_made_outside_hetros_in_this_process_is_refused_by_name() -> None:
    """Cyclone makes a domain once per process; hetros cannot apply its own interface and peers to
    one that other code made first, and says so instead of blaming the interface address."""
    number = free_domain()
    Peer(number)
    with pytest.raises(TransportError, match=rf"DDS domain {number} already exists in this process .*CYCLONEDDS_URI"):
        DdsDomain(number)
