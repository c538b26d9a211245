"""Nodes made in threads of the user's own: ros2/demos's topic_monitor (unchanged) makes its node in a
worker thread and finds its topics at run time; a thread of a node that raises fails the launch."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path
from typing import Any

import yaml

from tests.support.cli import hetros_in

DEMOS = Path(__file__).resolve().parents[1] / "data" / "ros2_demos"



def test_topic_monitor_with_its_reliability_demo(tmp_path: Path) -> None:
    """reliability_demo_launch.py's two publishers, imported; the topics their command lines name and the
    monitor's endpoints written in as `hetros check` asks (the code names them at run time); the monitor,
    run as `ros2 run topic_monitor topic_monitor` would, makes its node in a thread and subscribes to what
    get_topic_names_and_types() finds."""
    done = hetros_in("import", "ros2launch", str(DEMOS / "topic_monitor" / "launch" / "reliability_demo_launch.py"),
                   "-o", str(tmp_path / "project.yaml"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "project.yaml").read_text())
    unresolved = hetros_in("check", str(tmp_path / "project.yaml"), cwd=tmp_path)
    assert unresolved.returncode != 0 and "placeholder" in unresolved.stdout + unresolved.stderr
    nodes = project["nodes"]
    assert [node["args"] for node in nodes.values()] == [["sensor", "--best-effort"], ["critical"]]
    nodes["data_publisher"]["publish"] = {"/sensor_data_best_effort": "std_msgs/msg/Header"}
    nodes["data_publisher_2"]["publish"] = {"/critical_data": "std_msgs/msg/Header"}
    project["targets"]["monitor"] = {"kind": "process"}
    nodes["topic_monitor"] = {
        "run": "topic_monitor.scripts.topic_monitor:main", "target": "monitor",
        "subscribe": {"/sensor_data_best_effort": "std_msgs/msg/Header", "/critical_data": "std_msgs/msg/Header"},
        "publish": {"/reception_rate/sensor_data_best_effort_": "std_msgs/msg/Float32",
                    "/reception_rate/critical_data_": "std_msgs/msg/Float32"}}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    checked = hetros_in("check", str(tmp_path / "project.yaml"), cwd=tmp_path)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    monitor = re.findall(r"^\[INFO\] \[[\d.]+\] \[topic_monitor\]: (.*)$", done.stderr, re.MULTILINE)
    assert "Subscribing to topic: /critical_data" in monitor and \
        "Subscribing to topic: /sensor_data_best_effort" in monitor, done.stderr
    assert "Publishing reception rate on topic: reception_rate/critical_data_" in monitor
    assert "/critical_data: Alive" in monitor and "/sensor_data_best_effort: Alive" in monitor, done.stderr
    assert "/critical_data: 3" in monitor and "/sensor_data_best_effort: 3" in monitor, done.stderr


def test_a_thread_of_a_node_that_raises_fails_the_launch(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import threading

        import rclpy
        from std_msgs.msg import String


        def work():
            node = rclpy.create_node('worker')  # the node of this process, from a thread of the code's own
            node.create_publisher(String, 'chatter', 10).publish(String(data='from a thread'))
            raise ValueError('the worker broke')


        def main():
            rclpy.init()
            thread = threading.Thread(target=work, name='worker-thread')
            thread.start()
            thread.join()
        """))
    (tmp_path / "project.yaml").write_text(
        "name: threads\ntargets: {p: {kind: process}}\n"
        "nodes:\n  worker: {run: nodes:main, target: p, publish: {/chatter: std_msgs/msg/String}}\n")
    done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "10", cwd=tmp_path)
    assert done.returncode != 0, done.stderr
    assert "thread worker-thread of node worker raised" in done.stderr
    assert "ValueError: the worker broke" in done.stderr
    assert "a thread node worker started raised" in done.stderr


def test_an_optional_nodes_failure_ends_nothing(tmp_path: Path) -> None:
    """`optional: true`: the node's failure (here, a thread of it) is reported, the graph goes on and the
    launch exits 0; the same node without it ends the launch non-zero."""
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        import threading

        import rclpy


        def broken():
            def work():
                rclpy.create_node('worker')
                raise ValueError('the worker broke')
            rclpy.init()
            thread = threading.Thread(target=work, name='worker-thread')
            thread.start()
            thread.join()


        def steady(node):
            for i in node.rate(10.0):
                if i == 15:
                    node.log.info('still running')
        """))
    for optional in (True, False):
        (tmp_path / "project.yaml").write_text(
            "name: optional\ntargets: {a: {kind: process}, b: {kind: process}}\nnodes:\n"
            f"  broken: {{run: nodes:broken, target: a, optional: {str(optional).lower()}}}\n"
            "  steady: {run: nodes:steady, target: b}\n")
        done = hetros_in("launch", str(tmp_path / "project.yaml"), "--duration", "3", cwd=tmp_path)
        assert "ValueError: the worker broke" in done.stderr
        if optional:
            assert done.returncode == 0, done.stderr
            assert "it is optional: the graph goes on" in done.stderr and "still running" in done.stderr
        else:
            assert done.returncode != 0 and "still running" not in done.stderr, done.stderr
