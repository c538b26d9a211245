"""QoS written in code against the project file's: a delivery policy the code chose that the topic's QoS
contradicts is refused, by `hetros check` where the code fixes it and by the launch where the code
computes it (ros2/demos's talker_qos, best effort unless --reliable), naming both places."""

from __future__ import annotations

import os
import re
import textwrap
from pathlib import Path

import yaml

from tests.support.cli import hetros_in

DEMOS = Path(__file__).resolve().parents[1] / "data" / "ros2_demos"



def test_check_refuses_a_topic_qos_the_code_contradicts(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import rclpy
        from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data
        from std_msgs.msg import String


        def talker():
            rclpy.init()
            node = rclpy.create_node('talker')
            node.create_publisher(String, 'chatter', QoSProfile(depth=5, reliability=ReliabilityPolicy.BEST_EFFORT))
            rclpy.spin(node)


        def listener():
            rclpy.init()
            node = rclpy.create_node('listener')
            node.create_subscription(String, 'chatter', print, qos_profile_sensor_data)
            rclpy.spin(node)
        """))
    project = {"name": "qos", "nodes": {
        "talker": {"run": "nodes:talker", "publish": {"/chatter": "std_msgs/msg/String"}},
        "listener": {"run": "nodes:listener", "subscribe": {"/chatter": "std_msgs/msg/String"}}},
        "topics": {"/chatter": {"reliability": "reliable", "history": "keep_last", "depth": 5}}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project, sort_keys=False))
    done = hetros_in("check", str(tmp_path / "project.yaml"), cwd=tmp_path)
    assert done.returncode == 1
    text = done.stdout + done.stderr
    # the publisher's best effort is refused; the subscription's is served by a stronger offer, as ROS 2 does
    assert "topics./chatter: nodes.py:9: node talker's publish endpoint asks reliability best_effort (the project " \
           "file: reliable)" in text, text
    assert "project.yaml:" in text and "topics./chatter" in text, text
    assert "node listener's" not in text


def test_the_launch_refuses_qos_the_code_computes_against_the_projects(tmp_path: Path) -> None:
    """talker_qos is best effort unless --reliable: only the run knows."""
    talker_qos = DEMOS / "demo_nodes_py" / "demo_nodes_py" / "topics" / "talker_qos.py"
    project = {"name": "qos", "python_path": [os.path.relpath(DEMOS / "demo_nodes_py", tmp_path)],
               "targets": {"p": {"kind": "process"}},
               "nodes": {"talker_qos": {"run": "demo_nodes_py.topics.talker_qos:main", "target": "p",
                                        "args": ["-n", "2"], "publish": {"/chatter": "std_msgs/msg/String"}}},
               "topics": {"/chatter": {"reliability": "reliable", "history": "keep_last", "depth": 10}}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project, sort_keys=False))
    assert hetros_in("check", str(tmp_path / "project.yaml"), cwd=tmp_path).returncode == 0  # static: unknown
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "10", cwd=tmp_path)
    assert done.returncode != 0
    line = next(i for i, text in enumerate(talker_qos.read_text().splitlines(), 1) if "create_publisher" in text)
    assert f"{talker_qos}:{line}: the publisher of /chatter asks reliability best_effort (the project file: " \
           "reliable)" in done.stderr, done.stderr
    project["nodes"]["talker_qos"]["args"] = ["--reliable", "-n", "2"]  # what the project says: it runs
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project, sort_keys=False))
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "3", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert 'Publishing: "Hello World: 1"' in done.stderr


def test_a_best_effort_publisher_never_waits_for_a_slow_subscriber(tmp_path: Path) -> None:
    """On a topic the project gives no QoS (its transport: reliable, keep_all), a publisher whose code chose
    best effort drops what a full subscriber has no room for, as a ROS 2 best-effort writer, instead of
    waiting; the same talker asking nothing waits, and the listener hears every message."""
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import sys
        import time

        import rclpy
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from std_msgs.msg import Int32


        def talker():
            rclpy.init()
            node = rclpy.create_node('talker')
            best_effort = sys.argv[1:] == ['best_effort']
            qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT) if best_effort else 10
            publisher = node.create_publisher(Int32, '/numbers', qos)
            time.sleep(0.5)
            for i in range(200):
                publisher.publish(Int32(data=i))
            node.get_logger().info(f'sent 200, dropped {publisher.dropped}')


        def listener():
            rclpy.init()
            node = rclpy.create_node('listener')

            def slow(message):
                node.get_logger().info(f'heard {message.data}')
                time.sleep(0.01)
            node.create_subscription(Int32, '/numbers', slow, 10)
            rclpy.spin(node)
        """))
    for args, dropping in ((["best_effort"], True), ([], False)):
        project = {"name": "be", "targets": {"t": {"kind": "process"}, "l": {"kind": "process"}}, "nodes": {
            "talker": {"run": "nodes:talker", "target": "t", "args": args,
                       "publish": {"/numbers": "std_msgs/msg/Int32"}},
            "listener": {"run": "nodes:listener", "target": "l", "subscribe": {"/numbers": "std_msgs/msg/Int32"}}}}
        (tmp_path / "project.yaml").write_text(yaml.safe_dump(project, sort_keys=False))
        done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "5", cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        sent = re.search(r"\[talker\]: sent 200, dropped (\d+)", done.stderr)
        assert sent is not None, done.stderr
        heard = [int(n) for n in re.findall(r"\[listener\]: heard (\d+)$", done.stderr, re.MULTILINE)]
        assert heard == sorted(heard) and heard, done.stderr
        if dropping:
            assert int(sent.group(1)) > 0 and len(heard) + int(sent.group(1)) == 200, done.stderr
        else:
            assert sent.group(1) == "0" and heard == list(range(200)), done.stderr


def test_a_subscription_made_late_joins_as_ros2s_late_joiner(tmp_path: Path) -> None:
    """On a topic the project gives no QoS, a subscription the code makes after spinning for a while
    (in another process than the publisher) holds no publisher back before it exists, and gets of the
    earlier messages what its durability asks: none when volatile, the newest `depth` when
    transient_local."""
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import sys

        import rclpy
        from rclpy.qos import DurabilityPolicy, QoSProfile
        from std_msgs.msg import Int32


        def talker():
            rclpy.init()
            node = rclpy.create_node('talker')
            publisher = node.create_publisher(
                Int32, '/numbers', QoSProfile(depth=3, durability=DurabilityPolicy.TRANSIENT_LOCAL))
            count = iter(range(40))

            def tick():
                number = next(count, None)
                if number is not None:
                    publisher.publish(Int32(data=number))
                    node.get_logger().info(f'sent {number}')
            node.create_timer(0.02, tick)
            rclpy.spin(node)


        def listener():
            rclpy.init()
            node = rclpy.create_node('listener')
            durability = DurabilityPolicy.TRANSIENT_LOCAL if sys.argv[1:] == ['transient_local'] \\
                else DurabilityPolicy.VOLATILE

            def subscribe():
                timer.cancel()
                node.create_subscription(Int32, '/numbers', lambda m: node.get_logger().info(f'heard {m.data}'),
                                         QoSProfile(depth=3, durability=durability))
            timer = node.create_timer(3.0, subscribe)
            rclpy.spin(node)
        """))
    listeners = {"volatile": [], "transient_local": [37, 38, 39]}
    project = {"name": "late", "targets": {"t": {"kind": "process"}, **{k: {"kind": "process"} for k in listeners}},
               "nodes": {"talker": {"run": "nodes:talker", "target": "t",
                                    "publish": {"/numbers": "std_msgs/msg/Int32"}}}}
    for durability in listeners:
        project["nodes"][durability] = {"run": "nodes:listener", "target": durability, "args": [durability],
                                        "name": f"listener_{durability}",
                                        "subscribe": {"/numbers": "std_msgs/msg/Int32"}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project, sort_keys=False))
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    sent = [int(n) for n in re.findall(r"\[talker\]: sent (\d+)$", done.stderr, re.MULTILINE)]
    assert sent == list(range(40)), done.stderr  # the talker never waited for a listener not there yet
    for durability, expected in listeners.items():
        heard = [int(n) for n in re.findall(rf"\[listener_{durability}\]: heard (\d+)$", done.stderr, re.MULTILINE)]
        assert heard == expected, done.stderr
