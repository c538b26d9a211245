"""`kind: ros1` targets without a running master: checks, the plan, the runtime's refusals (log limits: test_log.py)."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from hetros import UndeclaredEndpointError
from hetros.plan import Plan
from hetros.project import check, load_project, plan
from hetros.runtime import Graph

NODES = textwrap.dedent('''
    def node(node):
        node.spin()
''')


def _project(tmp_path: Path, body: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text("name: r\ntargets: {main: {kind: thread}, old: {kind: ros1, cpus: [0]}}\n" + textwrap.dedent(body))
    return path


def test_a_ros1_node_must_use_types_ros1_has(tmp_path: Path) -> None:
    report = check(load_project(_project(tmp_path, """
        nodes:
          n: {run: nodes:node, target: old, publish: {/x: example_interfaces/msg/Int64}}
    """)))
    assert len(report.errors) == 1
    error = report.errors[0]
    assert "nodes.n.publish./x" in error and "runs on a ROS 1 target" in error
    assert "example_interfaces/msg/Int64 has no ROS 1 definition" in error


def test_ros1_endpoints_may_be_fed_from_outside_and_feed_hetros_nodes(tmp_path: Path) -> None:
    planned = plan(load_project(_project(tmp_path, """
        nodes:
          legacy: {run: nodes:node, target: old, subscribe: {/cmd: std_msgs/msg/String},
                   publish: {/odom: std_msgs/msg/String}, clients: {/ext: std_srvs/srv/Trigger},
                   services: {/reset: std_srvs/srv/Empty}}
          fresh: {run: nodes:node, target: main, subscribe: {/odom: std_msgs/msg/String},
                  clients: {/reset: std_srvs/srv/Empty}}
        topics:
          /odom: {durability: transient_local, depth: 3}
    """)))
    bridge = planned.nodes["hetros_ros1_bridge"]
    assert bridge.publish == {"/odom": "std_msgs/msg/String"}  # imported for fresh
    assert bridge.services == {"/reset": "std_srvs/srv/Empty"}
    assert bridge.parameters["export"] == {} and bridge.parameters["import"] == {"/odom": "std_msgs/msg/String"}
    assert set(planned.channels) == {"/odom", "/reset/_request", "/reset/_reply/fresh"}
    assert planned.ros1_master and planned.ros1_qos["/odom"].depth == 3
    again = Plan.from_json(planned.to_json())
    assert again.ros1_qos == planned.ros1_qos and again.ros1_host == "127.0.0.1"
    assert again.speaks_ros1("legacy") and not again.speaks_ros1("fresh")
    assert again.process_of("legacy") == "old"


def test_a_ros1_node_cannot_open_what_it_did_not_declare(tmp_path: Path) -> None:
    planned = plan(load_project(_project(tmp_path, """
        nodes:
          legacy: {run: nodes:node, target: old, publish: {/odom: std_msgs/msg/String}}
    """)))
    graph = Graph(planned, "old")
    try:
        with pytest.raises(UndeclaredEndpointError, match=r"nodes\.legacy\.publish"):
            graph.open_writer("/other", "legacy", "std_msgs/msg/String")
        with pytest.raises(UndeclaredEndpointError, match=r"nodes\.legacy\.subscribe"):
            graph.open_reader("/odom", "legacy", "std_msgs/msg/String", lambda: None)
    finally:
        graph.close()
