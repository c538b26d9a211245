"""A node's parameter services (``/node/get_parameters`` and the rest): ROS 2's answers, hand-computed; the
project file's parameters for a hetros node, rclpy's rules for an rclpy node; planned only where a node
calls them."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from hetros import Node
from hetros.msg import registry
from hetros.project import load_project, plan
from hetros.runtime import from_value_message, kind_of, listed, ros_main, to_value_message

NAMES = ["a", "b.c", "b.d.e", "f.g"]


@pytest.mark.parametrize(("prefixes", "depth", "names", "prefixes_found"), [
    ([], 0, NAMES, ["b", "b.d", "f"]),  # everything (DEPTH_RECURSIVE, no prefix)
    ([], 1, ["a"], []),  # names with no dot
    ([], 2, ["a", "b.c", "f.g"], ["b", "f"]),
    (["b"], 0, ["b.c", "b.d.e"], ["b", "b.d"]),  # every level under b
    (["b"], 1, ["b.c"], ["b"]),  # one level under b: d.e is two
    (["a", "f"], 1, ["a", "f.g"], ["f"]),
    (["x"], 0, [], []),
])
def test_list_parameters_answers_as_ros_2(prefixes: list[str], depth: int, names: list[str],
                                          prefixes_found: list[str]) -> None:
    assert listed(NAMES, prefixes, depth) == (names, prefixes_found)


@pytest.mark.parametrize(("value", "kind"), [
    (True, 1), (7, 2), (2.5, 3), ("hi", 4), ([b"\x01", b"\x02"], 5), ([True, False], 6), ([1, 2], 7),
    ([1.5], 8), (["x", "y"], 9), (None, 0)])
def test_a_value_keeps_its_kind_through_a_parameter_value_message(value: Any, kind: int) -> None:
    assert kind_of(value) == kind
    message = to_value_message(value)
    assert message.type == kind
    back = from_value_message(message)
    assert back == value and type(back) is type(value)


def _call(node: Node, service: str, request: Any) -> Any:
    _srv_type, handler = node.parameter_services[f"/{node.name}/{service}"]
    return handler(request)


def _srv(name: str) -> Any:
    return registry().get_service(f"rcl_interfaces/srv/{name}")


def _parameter(name: str, value: Any) -> Any:
    return registry().get("rcl_interfaces/msg/Parameter")(name=name, value=to_value_message(value))


def test_a_hetros_node_answers_for_its_project_parameters_and_keeps_their_types() -> None:
    node = Node("camera", parameters={"rate": 10.0, "frame": "cam", "level.low": 1})
    try:
        listed_ = _call(node, "list_parameters", _srv("ListParameters").Request())
        assert list(listed_.result.names) == ["rate", "frame", "level.low"]
        assert list(listed_.result.prefixes) == ["level"]
        got = _call(node, "get_parameters", _srv("GetParameters").Request(names=["frame", "rate"]))
        assert [from_value_message(v) for v in got.values] == ["cam", 10.0]
        missing = _call(node, "get_parameters", _srv("GetParameters").Request(names=["frame", "nope"]))
        assert list(missing.values) == []  # as ROS 2: one unknown name, no values
        types = _call(node, "get_parameter_types", _srv("GetParameterTypes").Request(names=["rate", "frame"]))
        assert list(types.types) == [3, 4]

        set_ = _srv("SetParameters").Request(parameters=[_parameter("rate", 20), _parameter("frame", 3),
                                                          _parameter("gain", 1.0), _parameter("frame", None)])
        results = _call(node, "set_parameters", set_).results
        assert [r.successful for r in results] == [True, False, False, False]
        assert results[1].reason == "parameter 'frame' of node 'camera' is a str, not a int"
        assert "has no parameter 'gain': declare it under nodes.camera.parameters" in results[2].reason
        assert "cannot be unset" in results[3].reason
        assert node.get_parameter("rate") == 20.0 and isinstance(node.get_parameter("rate"), float)

        atomically = _srv("SetParametersAtomically").Request(parameters=[_parameter("rate", 5.0),
                                                                         _parameter("frame", 1)])
        assert not _call(node, "set_parameters_atomically", atomically).result.successful
        assert node.get_parameter("rate") == 20.0  # all or nothing
    finally:
        node.close()


@pytest.fixture
def rclpy_node() -> Iterator[tuple[Node, Any]]:
    from hetros.compat.rclpy.node import Node as RclpyNode

    hetros = Node("board", parameters={"preset": 3})
    with ros_main(hetros):
        yield hetros, RclpyNode
    hetros.close()


def test_an_rclpy_nodes_parameter_services_follow_rclpys_rules(rclpy_node: tuple[Node, Any]) -> None:
    hetros, RclpyNode = rclpy_node
    strict = RclpyNode("board")
    strict.declare_parameter("width", 640)
    seen: list[list[str]] = []
    strict.add_post_set_parameters_callback(lambda params: seen.append([p.name for p in params]))
    request = _srv("SetParameters").Request(parameters=[_parameter("width", 320), _parameter("height", 1),
                                                         _parameter("width", "wide"), _parameter("width", None)])
    results = _call(hetros, "set_parameters", request).results
    assert [r.successful for r in results] == [True, False, False, False]
    assert "not declared" in results[1].reason  # undeclared ones are refused unless allowed
    assert "is a int, not a str" in results[2].reason  # a declared parameter keeps its type
    assert "cannot be unset" in results[3].reason
    assert seen == [["width"]] and strict.get_parameter("width").value == 320
    listed_ = _call(hetros, "list_parameters", _srv("ListParameters").Request())
    # rclpy's declared ones (the project's preset is not declared), use_sim_time first as on every ROS 2 node
    assert list(listed_.result.names) == ["use_sim_time", "width"]


def test_an_rclpy_node_that_allows_undeclared_ones_takes_and_undeclares_them(rclpy_node: tuple[Node, Any]) -> None:
    hetros, RclpyNode = rclpy_node
    board = RclpyNode("board", allow_undeclared_parameters=True,
                      automatically_declare_parameters_from_overrides=True)
    assert board.has_parameter("preset")
    request = _srv("SetParameters").Request(parameters=[_parameter("anything", 1), _parameter("anything", "one"),
                                                         _parameter("anything", None), _parameter("gone", None)])
    assert [r.successful for r in _call(hetros, "set_parameters", request).results] == [True, True, True, True]
    assert not board.has_parameter("anything")
    described = _call(hetros, "describe_parameters", _srv("DescribeParameters").Request(names=["preset"]))
    assert [(d.name, d.type) for d in described.descriptors] == [("preset", 2)]


def test_parameter_services_are_planned_only_where_a_node_calls_them(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text("def run(node):\n    pass\n")
    clients = {f"/ns/board/{service}": f"rcl_interfaces/srv/{kind}" for service, kind in
               (("get_parameters", "GetParameters"), ("set_parameters", "SetParameters"))}
    (tmp_path / "project.yaml").write_text(yaml.safe_dump({"name": "p", "nodes": {
        "blackboard": {"run": "nodes:run", "namespace": "ns", "name": "board"},
        "caller": {"run": "nodes:run", "clients": clients},
        "quiet": {"run": "nodes:run"}}}))
    planned = plan(load_project(tmp_path / "project.yaml"))
    assert planned.nodes["blackboard"].services == clients
    assert planned.nodes["quiet"].services == {}
    assert {"/ns/board/get_parameters/_request", "/ns/board/get_parameters/_reply/caller"} <= set(planned.channels)
    servers = planned.parameter_servers()
    assert servers["/ns/board/list_parameters"] == ("blackboard", "rcl_interfaces/srv/ListParameters")
    assert servers["/quiet/set_parameters"] == ("quiet", "rcl_interfaces/srv/SetParameters")
