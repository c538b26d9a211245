"""A ROS 1 bag, written by Debian's rosbag, played by `hetros play --launch` into a graph where an rclpy
node in hetros and a stock rospy listener (joined through `external: ros1:`) both hear every message."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from tests.support.ros1 import ROS_PYTHON, needs_ros1, stop

COUNT = 12

WRITE_BAG = textwrap.dedent("""
    import sys, rosbag, rospy
    from std_msgs.msg import String
    with rosbag.Bag(sys.argv[1], "w") as bag:
        for i in range({count}):
            bag.write("/chatter", String(data="bagged %d" % i), rospy.Time(100, i * 50_000_000))
""").format(count=COUNT)

ROSPY_LISTENER = textwrap.dedent("""
    import rospy
    from std_msgs.msg import String
    rospy.init_node("stock_listener")
    rospy.Subscriber("/chatter", String, lambda m: print("ros1 heard " + m.data, flush=True))
    print("ready", flush=True)
    rospy.spin()
""")

HETROS_LISTENER = textwrap.dedent("""
    import rclpy
    from rclpy.node import Node
    from std_msgs.msg import String


    def main():
        with rclpy.init():
            node = Node('listener')
            node.create_subscription(String, 'chatter', lambda m: node.get_logger().info('heard ' + m.data), 10)
            rclpy.spin(node)
""")


@needs_ros1
def test_a_debian_bag_plays_into_hetros_and_a_stock_rospy_listener(master: tuple[str, dict[str, str]],
                                                                    tmp_path: Path) -> None:
    uri, env = master
    bag = tmp_path / "chatter.bag"
    (tmp_path / "write_bag.py").write_text(WRITE_BAG)
    subprocess.run([ROS_PYTHON, str(tmp_path / "write_bag.py"), str(bag)], env=env, check=True, timeout=60)
    (tmp_path / "listener.py").write_text(HETROS_LISTENER)
    (tmp_path / "stock_listener.py").write_text(ROSPY_LISTENER)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: bag_to_ros1
        nodes:
          listener: {{run: listener:main, subscribe: {{/chatter: std_msgs/msg/String}}}}
        topics:
          /chatter: {{history: keep_last, depth: 100}}
        external:
          ros1: {{master: '{uri}', export: [/chatter]}}
    """))
    stock = subprocess.Popen([ROS_PYTHON, str(tmp_path / "stock_listener.py")], env=env, stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, text=True)
    try:
        assert stock.stdout is not None and stock.stdout.readline().strip() == "ready"
        time.sleep(0.5)
        done = subprocess.run([sys.executable, "-m", "hetros", "play", str(bag), "--launch",
                               str(tmp_path / "project.yaml")],
                              cwd=tmp_path, capture_output=True, text=True, timeout=180, check=False)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline:
            time.sleep(0.5)
    finally:
        heard_by_ros1 = stop(stock)
    assert done.returncode == 0, done.stderr
    expected = [f"bagged {i}" for i in range(COUNT)]
    assert re.findall(r"\[listener\]: heard (bagged \d+)$", done.stderr, re.MULTILINE) == expected, done.stderr
    assert re.findall(r"^ros1 heard (bagged \d+)$", heard_by_ros1, re.MULTILINE) == expected, heard_by_ros1
