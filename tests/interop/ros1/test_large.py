"""A 6 MiB sensor_msgs/Image both ways between stock rospy and a hetros node on a `kind: ros1` target."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time
from pathlib import Path

from tests.support.ros1 import ROS_PYTHON, needs_ros1, stop

WIDTH, HEIGHT = 2048, 1024  # rgb8: 6 MiB
# the same pixels on both sides, cheap to make in plain Python: a repeated digest
PIXELS = 'hashlib.sha256(b"hetros").digest() * (3 * 2048 * 1024 // 32)'
SUMMARY = ('"%d %d %s %d %d %s %d.%09d %s" % (m.height, m.width, m.encoding, m.is_bigendian, m.step, '
           'm.header.frame_id, {sec}, {nsec}, hashlib.md5(bytes(m.data)).hexdigest())')

NODES = textwrap.dedent(f'''
    import hashlib
    from hetros.interfaces.builtin_interfaces.msg import Time
    from hetros.interfaces.std_msgs.msg import Header
    from hetros.interfaces.sensor_msgs.msg import Image
    import numpy as np

    def talker(node):
        pub = node.create_publisher(Image, "/from_hetros")
        data = np.frombuffer({PIXELS}, np.uint8)
        for _ in node.rate(4):
            pub.publish(Image(header=Header(stamp=Time(sec=12, nanosec=345), frame_id="hetros_cam"),
                              height={HEIGHT}, width={WIDTH}, encoding="rgb8", step={3 * WIDTH}, data=data))

    def listener(node):
        for m in node.create_subscription(Image, "/from_rospy"):
            with open(node.get_parameter("out"), "a") as out:
                out.write({SUMMARY.format(sec="m.header.stamp.sec", nsec="m.header.stamp.nanosec")} + "\\n")
''')

ROSPY = textwrap.dedent(f'''
    import hashlib, sys, time, rospy
    from sensor_msgs.msg import Image
    got = []
    rospy.init_node("image_peer")
    rospy.Subscriber("/from_hetros", Image, got.append, queue_size=2)
    pub = rospy.Publisher("/from_rospy", Image, queue_size=2)
    data = {PIXELS}
    start = time.time()
    while not got and time.time() - start < 30:
        m = Image(height={HEIGHT}, width={WIDTH}, encoding="rgb8", step={3 * WIDTH}, data=data)
        m.header.frame_id = "rospy_cam"
        m.header.stamp = rospy.Time(7, 89)
        pub.publish(m)
        time.sleep(0.25)
    for _ in range(8):  # let the hetros side hear a few
        pub.publish(m)
        time.sleep(0.25)
    m = got[0]
    print({SUMMARY.format(sec="m.header.stamp.secs", nsec="m.header.stamp.nsecs")})
''')


@needs_ros1
def test_a_6_mib_image_crosses_both_ways_byte_identical(master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    import hashlib

    uri, env = master
    pixels = hashlib.md5(hashlib.sha256(b"hetros").digest() * (3 * WIDTH * HEIGHT // 32)).hexdigest()
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: images
        targets: {{ros1: {{kind: ros1}}}}
        nodes:
          talker: {{run: nodes:talker, target: ros1, publish: {{/from_hetros: sensor_msgs/msg/Image}}}}
          listener: {{run: nodes:listener, target: ros1, subscribe: {{/from_rospy: sensor_msgs/msg/Image}},
                     parameters: {{out: {tmp_path / "got.txt"}}}}}
        external:
          ros1: {{master: '{uri}'}}
    """))
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml")],
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        (tmp_path / "peer.py").write_text(ROSPY)
        peer = subprocess.run([ROS_PYTHON, str(tmp_path / "peer.py")], env=env, capture_output=True, text=True,
                              timeout=90, check=False)
        assert peer.stdout.strip() == f"1024 2048 rgb8 0 6144 hetros_cam 12.000000345 {pixels}", \
            peer.stdout + peer.stderr[-2000:]
        got = tmp_path / "got.txt"
        deadline = time.monotonic() + 20
        while not (got.exists() and got.read_text().strip()) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert got.read_text().splitlines()[0] == f"1024 2048 rgb8 0 6144 rospy_cam 7.000000089 {pixels}"
    finally:
        output = stop(launch, 30)
    assert "Traceback" not in output, output
