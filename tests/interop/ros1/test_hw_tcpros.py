"""Hardware TCPROS: an fpga target (co-simulated) is a ROS 1 node; stock ROS 1 reads and feeds its frames.

``examples/hw_tcpros``: hardware nodes publish /chatter and /points, framed for ROS 1 by the
target's RTL; a compiled roscpp listener and ``rostopic echo`` hear /chatter; a rospy script
checks every frame of both topics byte for byte against rospy's own serialization of the message
it decodes; a stock rospy talker publishes /ros1_chatter, whose frames the hardware reads.
"""

from __future__ import annotations

import random
import re
import struct
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from tests.support.ros1 import ROS_PYTHON, compile_roscpp, needs_ros1, needs_roscpp, ros1_master, rospy_talker, stop

EXAMPLE = Path(__file__).parents[3] / "examples" / "hw_tcpros"

# every frame of a topic as rospy receives it (AnyMsg: the bytes unparsed), against rospy's own bytes
FRAMES = textwrap.dedent("""
    import sys, time, rospy
    from io import BytesIO
    from std_msgs.msg import String
    from geometry_msgs.msg import PointStamped
    rospy.init_node("frame_checker")
    kinds = {"/chatter": String, "/points": PointStamped}
    seen = {topic: 0 for topic in kinds}
    def check(topic):
        def on_frame(raw):
            message = kinds[topic]()
            message.deserialize(raw._buff)
            again = BytesIO()
            message.serialize(again)
            if again.getvalue() != raw._buff:
                print("MISMATCH", topic, raw._buff.hex(), again.getvalue().hex(), flush=True)
            else:
                seen[topic] += 1
                if seen[topic] <= 2:
                    print("frame", topic, repr(message).replace(chr(10), " "), flush=True)
        return on_frame
    for topic in kinds:
        rospy.Subscriber(topic, rospy.AnyMsg, check(topic))
    start = time.time()
    while min(seen.values()) < 5 and time.time() - start < 90:
        time.sleep(0.05)
    print("checked", seen, flush=True)
""")

TALKER = rospy_talker("ros1_talker", "/ros1_chatter", "from rospy", 10)


@needs_ros1
@needs_roscpp
def test_the_fpga_is_a_ros1_node_publishing_and_subscribing_in_hardware(tmp_path: Path) -> None:
    listener = compile_roscpp(Path(__file__).with_name("data") / "listener.cpp", tmp_path / "listener")
    (tmp_path / "frames.py").write_text(FRAMES)
    (tmp_path / "talker.py").write_text(TALKER)
    heard = tmp_path / "out" / "hw_tcpros" / "heard.txt"
    for master in ros1_master("rosmaster"):
        _uri, env = master
        peers = [subprocess.Popen([str(listener), "5"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                  text=True),
                 subprocess.Popen([ROS_PYTHON, str(tmp_path / "frames.py")], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True),
                 subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)]
        launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLE / "project.yaml")],
                                  cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            echoed = subprocess.run(["/usr/bin/rostopic", "echo", "-n", "3", "/chatter"], env=env,
                                    capture_output=True, text=True, timeout=180, check=False).stdout
            deadline = time.monotonic() + 120
            while peers[1].poll() is None or peers[0].poll() is None:
                assert time.monotonic() < deadline, "the ROS 1 peers did not hear the hardware in time"
                time.sleep(0.2)
            while not heard.exists() or heard.read_text().count("from rospy") < 3:
                assert time.monotonic() < deadline and launch.poll() is None, "the hardware heard no rospy talker"
                time.sleep(0.2)
        finally:
            outputs = [stop(p) for p in peers]
            logged = stop(launch, grace=30)
        roscpp, frames, _talker = outputs
        assert peers[0].returncode == 0, roscpp + logged
        assert roscpp.count("I heard: [hello world") == 5, roscpp
        assert 'data: "hello world' in echoed, echoed + logged
        # each topic at least 5 frames, all as sent (one may run ahead while the other reaches 5)
        counts = re.search(r"checked \{'/chatter': (\d+), '/points': (\d+)\}", frames)
        assert "MISMATCH" not in frames and counts is not None and min(map(int, counts.groups())) >= 5, frames
        # which frames the checker prints first depends on when it connected: each must be frame N's values
        points = re.findall(r'frame_id: "frame (\d+)" point:    x: ([-\d.]+)   y: ([-\d.]+)   z: 3.25', frames)
        assert points and "seq: 0" in frames, frames
        assert all(float(x) == 0.5 * int(n) and float(y) == -float(n) for n, x, y in points), points
        assert ("ROS 1 node /hw_tcpros_fpga (hardware TCPROS: publishes /chatter, /points, subscribes "
                "/ros1_chatter)") in logged, logged
        lines = heard.read_text().splitlines()
        assert lines[0].startswith("heard from rospy"), lines


def _malformed(rng: random.Random) -> bytes:
    """One TCPROS frame whose length prefix is right but whose std_msgs/String is not."""
    kind = rng.randrange(3)
    if kind == 0:  # a string length running past the frame (a 28-byte frame claiming a huge string)
        body = struct.pack("<I", rng.randrange(25, 2**32)) + rng.randbytes(24)
    elif kind == 1:  # bytes left over after the string
        text = rng.randbytes(rng.randrange(0, 20))
        body = struct.pack("<I", len(text)) + text + rng.randbytes(rng.randrange(1, 9))
    else:  # shorter than the length field itself
        body = rng.randbytes(rng.randrange(0, 4))
    return struct.pack("<I", len(body)) + body


def test_the_hardware_subscriber_survives_a_thousand_malformed_frames(tmp_path: Path) -> None:
    """A ROS 1 publisher of /ros1_chatter sends 1,000 malformed frames, then good ones: each bad one is
    refused before the target's deframer sees it (logged, counted), and the good ones still reach the
    hardware and come out of it (one such frame used to stop the launch)."""
    from hetros.msg import registry
    from hetros.transport.tcpros import Ros1Peer, Ros1Type

    heard = tmp_path / "out" / "hw_tcpros" / "heard.txt"
    for master in ros1_master("hetros"):
        uri, env = master
        rogue = Ros1Peer("/rogue", uri)
        kind = Ros1Type(registry(), "std_msgs/msg/String")
        publication = rogue.advertise("/ros1_chatter", kind)
        launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLE / "project.yaml")],
                                  cwd=tmp_path, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            deadline = time.monotonic() + 120
            while not publication.subscribers:
                assert time.monotonic() < deadline and launch.poll() is None, "the hardware never subscribed"
                time.sleep(0.1)
            rng = random.Random(9)
            for _ in range(1000):
                publication.publish_frame(_malformed(rng))
            String = registry().get("std_msgs/msg/String")
            while not heard.exists() or "after the junk" not in heard.read_text():
                assert time.monotonic() < deadline and launch.poll() is None, "good frames stopped reaching hardware"
                payload = kind.serialize(String(data="after the junk"))
                publication.publish_frame(struct.pack("<I", len(payload)) + bytes(payload))
                time.sleep(0.2)
            assert launch.poll() is None
        finally:
            rogue.close()
            logged = stop(launch, grace=30)
        assert "dropped a malformed frame from ROS 1 (1000 so far)" in logged, logged
        assert "HardwareError" not in logged and "Traceback" not in logged, logged
