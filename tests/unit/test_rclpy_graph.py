"""rclpy's graph queries answered from the plan, and rclpy nodes made in threads of the code's own."""

from __future__ import annotations

import threading
from pathlib import Path
from typing import Any

import pytest

from hetros import NodeError
from hetros.project import plan_file
from hetros.runtime import Graph, Node, ros_main


def _graph(tmp_path: Path) -> Graph:
    (tmp_path / "nodes.py").write_text("def f(node):\n    pass\n")
    (tmp_path / "project.yaml").write_text(
        "name: g\nnodes:\n"
        "  talker: {run: nodes:f, name: speaker, namespace: /r2, publish: {/chatter: std_msgs/msg/String}}\n"
        "  listener: {run: nodes:f, subscribe: {/chatter: std_msgs/msg/String}, services: {/add: "
        "example_interfaces/srv/AddTwoInts}}\n"
        "topics:\n  /chatter: {reliability: best_effort, history: keep_last, depth: 3}\n")
    return Graph(plan_file(tmp_path / "project.yaml"))


def test_graph_queries_come_from_the_plan(tmp_path: Path) -> None:
    import hetros.compat.rclpy as rclpy

    graph = _graph(tmp_path)
    seen: dict[str, Any] = {}
    with ros_main(Node("listener", graph)):
        node = rclpy.create_node("listener")
        seen["nodes"] = node.get_node_names_and_namespaces()
        seen["topics"] = node.get_topic_names_and_types()
        seen["counts"] = (node.count_publishers("/chatter"), node.count_subscribers("/chatter"))
        seen["services"] = dict(node.get_service_names_and_types())
        [info] = node.get_publishers_info_by_topic("/chatter")
    assert seen["nodes"] == [("listener", "/"), ("speaker", "/r2")]
    assert seen["topics"] == [("/chatter", ["std_msgs/msg/String"])]
    assert seen["counts"] == (1, 1)
    assert seen["services"]["/add"] == ["example_interfaces/srv/AddTwoInts"]
    assert seen["services"]["/r2/speaker/get_parameters"] == ["rcl_interfaces/srv/GetParameters"]
    assert (info.node_name, info.node_namespace, info.topic_type) == ("speaker", "/r2", "std_msgs/msg/String")
    assert info.qos_profile.depth == 3 and info.qos_profile.reliability.name == "BEST_EFFORT"


def test_a_thread_of_the_codes_own_makes_the_processs_node(tmp_path: Path) -> None:
    import hetros.compat.rclpy as rclpy

    graph = _graph(tmp_path)
    made: list[Any] = []

    def worker() -> None:
        made.append(rclpy.create_node("in_a_thread"))

    hetros = Node("listener", graph)
    with ros_main(hetros):
        thread = threading.Thread(target=worker)
        thread.start()
        thread.join(10)
    # the process's node (the project gives it no name: the code's stands)
    assert [(n._hetros, n.get_fully_qualified_name()) for n in made] == [(hetros, "/in_a_thread")]


def test_a_thread_in_a_process_of_several_ros_nodes_is_refused(tmp_path: Path) -> None:
    import hetros.compat.rclpy as rclpy

    graph = _graph(tmp_path)
    failures: list[BaseException] = []
    entered = threading.Barrier(3)

    def node_main(node: Node) -> None:
        with ros_main(node):
            entered.wait(10)
            entered.wait(10)

    mains = [threading.Thread(target=node_main, args=(Node(n, graph),)) for n in ("listener", "talker")]
    for thread in mains:
        thread.start()
    entered.wait(10)

    def worker() -> None:
        try:
            rclpy.create_node("x")
        except NodeError as exc:
            failures.append(exc)

    thread = threading.Thread(target=worker)
    thread.start()
    thread.join(10)
    entered.wait(10)
    for thread in mains:
        thread.join(10)
    assert len(failures) == 1 and "running 2 ROS nodes (listener, talker)" in str(failures[0])
    with pytest.raises(NodeError, match="runs inside `hetros launch` only"):
        rclpy.create_node("outside")
