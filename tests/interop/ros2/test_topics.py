"""Topics exported to and imported from ROS 2: an independent peer on the cyclonedds binding,
with ROS 2's DDS names and its own type classes, sees what a stock ROS 2 node would."""

from __future__ import annotations

import subprocess
import textwrap
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
from rosbags.typesys import Stores, get_typestore

from tests.support.ros2 import (
    Header,
    Image,
    Log,
    Peer,
    String,
    Time,
    free_domain,
    launched,
    raw_samples,
    wait_for,
    write_project,
)

JAZZY = get_typestore(Stores.ROS2_JAZZY)

NODES = textwrap.dedent('''
    import time
    import numpy as np
    from hetros.interfaces.std_msgs.msg import String, Header
    from hetros.interfaces.sensor_msgs.msg import Image
    from hetros.interfaces.builtin_interfaces.msg import Time

    def talker(node):
        pub = node.create_publisher(String, "/chatter")
        i = 0
        while not node.graph.stop.is_set():
            pub.publish(String(data=f"hello {i}"))
            i += 1
            time.sleep(0.05)

    def camera(node):
        pub = node.create_publisher(Image, "/image")
        pixels = (np.arange(640 * 480 * 3) % 251).astype(np.uint8)
        while not node.graph.stop.is_set():
            pub.publish(Image(header=Header(stamp=Time(sec=7, nanosec=9), frame_id="cam"), height=480,
                              width=640, encoding="rgb8", is_bigendian=0, step=640 * 3, data=pixels.copy()))
            time.sleep(0.2)

    def recorder(node):
        with open(node.get_parameter("out"), "a") as out:
            def heard(message):
                out.write(f"{message.data}\\n")
                out.flush()
            node.create_subscription(String, "/from_ros2", heard)
            def image(message):
                out.write(f"image {message.width}x{message.height} {message.encoding} "
                          f"{int(np.asarray(message.data, dtype=np.int64).sum())}\\n")
                out.flush()
            node.create_subscription(Image, "/image_in", image)
            node.spin()
''')


@pytest.fixture
def graph(tmp_path: Path) -> Iterator[tuple[int, Path, subprocess.Popen[str]]]:
    domain = free_domain()
    project = write_project(tmp_path, NODES, f"""
        name: ros2_demo
        targets: {{main: {{kind: thread}}, worker: {{kind: process}}}}
        nodes:
          talker: {{run: nodes:talker, target: worker, publish: {{/chatter: std_msgs/msg/String}}}}
          camera: {{run: nodes:camera, target: worker, publish: {{/image: sensor_msgs/msg/Image}}}}
          recorder: {{run: nodes:recorder, target: main, parameters: {{out: {tmp_path / "got.txt"}}},
                     subscribe: {{/from_ros2: std_msgs/msg/String, /image_in: sensor_msgs/msg/Image}}}}
        external:
          ros2: {{domain: {domain}, export: [/chatter, /image], import: [/from_ros2, /image_in]}}
    """)
    with launched(project) as launch:
        yield domain, tmp_path / "got.txt", launch


def test_hetros_topics_reach_a_ros2_peer_byte_identical(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    domain, _got, launch = graph
    peer = Peer(domain)
    chatter = peer.reader("rt/chatter", String)
    image = peer.reader("rt/image", Image)
    raw = wait_for(lambda: raw_samples(chatter), 20, "rt/chatter from hetros")
    assert raw[0][:4] == b"\x00\x01\x00\x00"  # XCDR1, little endian: what stock ROS 2 accepts
    text = JAZZY.deserialize_cdr(raw[0], "std_msgs/msg/String").data
    assert text.startswith("hello ")
    assert raw[0][:4 + 4 + len(text) + 1] == JAZZY.serialize_cdr(
        JAZZY.types["std_msgs/msg/String"](data=text), "std_msgs/msg/String")[:4 + 4 + len(text) + 1]
    frames = wait_for(lambda: raw_samples(image), 20, "rt/image from hetros")
    frame = frames[0]
    assert frame[:4] == b"\x00\x01\x00\x00"
    decoded = JAZZY.deserialize_cdr(frame, "sensor_msgs/msg/Image")
    expected = JAZZY.types["sensor_msgs/msg/Image"](
        header=JAZZY.types["std_msgs/msg/Header"](stamp=JAZZY.types["builtin_interfaces/msg/Time"](sec=7, nanosec=9),
                                                  frame_id="cam"),
        height=480, width=640, encoding="rgb8", is_bigendian=0, step=1920,
        data=(np.arange(640 * 480 * 3) % 251).astype(np.uint8))
    reference = bytes(JAZZY.serialize_cdr(expected, "sensor_msgs/msg/Image"))
    assert bytes(frame[:len(reference)]) == reference
    assert len(frame) - len(reference) < 4  # only the padding to whole words
    assert decoded.width == 640
    # the binding's own deserializer (what its users would call) agrees
    typed = peer.reader("rt/chatter", String)
    sample = wait_for(lambda: typed.take(), 10, "a typed rt/chatter sample")
    assert sample[0].data.startswith("hello ")
    assert launch.poll() is None


def test_a_ros2_peer_reaches_hetros_subscribers(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    domain, got, launch = graph
    peer = Peer(domain)
    talker = peer.writer("rt/from_ros2", String)
    camera = peer.writer("rt/image_in", Image)
    wait_for(lambda: talker.get_matched_subscriptions() and camera.get_matched_subscriptions(), 20,
             "the hetros bridge to match the peer's writers")
    pixels = (np.arange(640 * 480 * 3) % 13).astype(np.uint8)
    for i in range(5):
        talker.write(String(data=f"from ROS 2 {i}"))
    camera.write(Image(header=Header(stamp=Time(sec=1, nanosec=2), frame_id="peer"), height=480, width=640,
                       encoding="rgb8", is_bigendian=0, step=1920, data=pixels.tolist()))
    expected = [f"from ROS 2 {i}" for i in range(5)] + [f"image 640x480 rgb8 {int(pixels.sum())}"]

    def arrived() -> bool:
        lines = got.read_text().splitlines() if got.exists() else []
        return all(line in lines for line in expected)

    wait_for(arrived, 20, "the peer's messages in the hetros recorder")
    lines = got.read_text().splitlines()
    assert [line for line in lines if line.startswith("from ROS 2")] == expected[:5]  # in order, once each
    assert launch.poll() is None


def test_the_graphs_log_records_reach_ros2_on_rosout(graph: tuple[int, Path, subprocess.Popen[str]]) -> None:
    """Every process' log lines, as rcl_interfaces/msg/Log on /rosout (what rqt_console and `ros2 topic echo
    /rosout` read)."""
    domain, _got, _launch = graph
    rosout = Peer(domain).reader("rt/rosout", Log)

    def bridge_said_hello() -> list[Log]:
        found.extend(rosout.take(100))
        return [r for r in found if r.name == "hetros_ros2_bridge" and r.msg.startswith("ROS 2 bridge on DDS domain")]

    found: list[Log] = []
    (record,) = wait_for(bridge_said_hello, 20, "the bridge's own log record on rt/rosout")
    assert record.level == 20 and record.stamp.sec > 1_700_000_000
    assert any(r.name == "launch" and "ready" in r.msg for r in found)  # the worker target's start, from its file
