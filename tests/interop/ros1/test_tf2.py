"""tf2 across ROS 1 and hetros: a stock rospy node broadcasting with Debian's tf2_ros (a moving frame on
/tf, a static one on /tf_static, latched) is heard through `external: ros1:` by an rclpy node running in
hetros, whose Buffer looks the chain up."""

from __future__ import annotations

import re
import subprocess
import sys
import textwrap
from pathlib import Path

from tests.support.cli import looked_at, private_env
from tests.support.ros1 import ROS_PYTHON, needs_ros1, stop

BROADCASTER = textwrap.dedent("""
    import rospy, tf2_ros
    from geometry_msgs.msg import TransformStamped
    rospy.init_node("ros1_broadcaster")
    static = tf2_ros.StaticTransformBroadcaster()
    s = TransformStamped()
    s.header.stamp = rospy.Time.now()
    s.header.frame_id, s.child_frame_id = "base_link", "laser"
    s.transform.translation.z = 0.25
    s.transform.rotation.w = 1.0
    static.sendTransform(s)
    moving = tf2_ros.TransformBroadcaster()
    rate = rospy.Rate(20)
    while not rospy.is_shutdown():
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id, t.child_frame_id = "odom", "base_link"
        t.transform.translation.x = 2.0
        t.transform.rotation.w = 1.0
        moving.sendTransform(t)
        rate.sleep()
""")

LISTENER = textwrap.dedent("""
    import rclpy
    from rclpy.node import Node
    from tf2_ros import Buffer, TransformListener, TransformException


    class Looker(Node):
        def __init__(self):
            super().__init__('looker')
            self.buffer = Buffer()
            self.listener = TransformListener(self.buffer, self)
            self.create_timer(0.5, self.look)

        def look(self):
            try:
                t = self.buffer.lookup_transform('odom', 'laser', rclpy.time.Time())
            except TransformException as exc:
                self.get_logger().info(f'not yet: {exc}')
                return
            v = t.transform.translation
            self.get_logger().info(f'laser in odom: {v.x:.2f} {v.y:.2f} {v.z:.2f}')


    def main():
        with rclpy.init():
            rclpy.spin(Looker())
""")


@needs_ros1
def test_a_stock_rospy_tf2_broadcaster_is_heard_by_a_hetros_listener(master: tuple[str, dict[str, str]],
                                                                      tmp_path: Path) -> None:
    uri, env = master
    (tmp_path / "broadcaster.py").write_text(BROADCASTER)
    (tmp_path / "looker.py").write_text(LISTENER)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: tf_from_ros1
        nodes:
          looker: {{run: looker:main, subscribe: {{/tf: tf2_msgs/msg/TFMessage, /tf_static: tf2_msgs/msg/TFMessage}}}}
        topics:
          /tf_static: {{durability: transient_local, history: keep_last, depth: 100}}
          /tf: {{history: keep_last, depth: 100}}
        external:
          ros1: {{master: '{uri}', import: [/tf, /tf_static]}}
    """))
    broadcaster = subprocess.Popen([ROS_PYTHON, str(tmp_path / "broadcaster.py")], env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True)
    look_env = private_env(tmp_path)
    try:
        with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                               "--duration", "10"], cwd=tmp_path, env=look_env, stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) as launch:
            try:
                echoed = looked_at(tmp_path, "tf", "echo", "odom", "laser", "--once", "--duration", "6")
                frames = looked_at(tmp_path, "tf", "frames", "--duration", "2")
                _stdout, stderr = launch.communicate(timeout=120)
            finally:
                launch.kill()
    finally:
        stop(broadcaster)
    assert launch.returncode == 0, stderr
    assert re.search(r"\[looker\]: laser in odom: 2\.00 0\.00 0\.25$", stderr, re.MULTILINE), stderr
    # the same tree from the command line: tf2_echo's and view_frames' answers for ROS 1's broadcaster
    assert "- Translation: [2.000, 0.000, 0.250]" in echoed, echoed
    assert "  laser  (static, broadcaster " in frames and re.search(r"  base_link  \(\d+\.\d\d Hz", frames), frames


