"""The project file's launch conveniences: namespaces, remaps, groups, instances, parameter files,
includes with arguments, and the errors each gives."""

from __future__ import annotations

from pathlib import Path

import pytest

from hetros import ProjectError
from hetros.plan import resolve_name
from hetros.project import check, load_project, plan

NODE = "run: case_nodes:talker\n"


def write(folder: Path, name: str, text: str) -> Path:
    path = folder / name
    path.write_text(text)
    return path


@pytest.mark.parametrize(("name", "namespace", "expected"), [
    ("chatter", "", "/chatter"), ("chatter", "/ns", "/ns/chatter"), ("/abs", "/ns", "/abs"),
    ("~/private", "/ns", "/ns/node/private"), ("~", "", "/node"), ("a/b", "/x/y", "/x/y/a/b"),
])
def test_names_resolve_as_ros_resolves_them(name: str, namespace: str, expected: str) -> None:
    assert resolve_name(name, namespace, "node") == expected


def test_remaps_apply_after_resolution() -> None:
    assert resolve_name("chatter", "/ns", "node", {"/ns/chatter": "/talk"}) == "/talk"


def test_namespaces_groups_instances_and_remaps_flatten(tmp_path: Path) -> None:
    project = load_project(write(tmp_path, "p.yaml", """
name: p
nodes:
  talker:
    run: case_nodes:talker
    namespace: robot
    remap: {chatter: /shared/chatter}
    publish: {chatter: std_msgs/msg/String, ~/status: std_msgs/msg/String}
  listener:
    run: case_nodes:listener
    subscribe: {chatter: std_msgs/msg/String}
    instances:
      left: {namespace: /left, name: ear}
      right: {namespace: /right, remap: {/right/chatter: /shared/chatter}}
groups:
  arm:
    namespace: /arm
    env: {ARM: "1"}
    nodes:
      driver: {run: case_nodes:talker, namespace: joint, publish: {state: std_msgs/msg/String}}
"""))
    nodes = project.model.nodes
    assert set(nodes) == {"talker", "left", "right", "driver"}
    assert set(nodes["talker"].publish) == {"/shared/chatter", "/robot/talker/status"}
    assert set(nodes["left"].subscribe) == {"/left/chatter"} and nodes["left"].name == "ear"
    assert set(nodes["right"].subscribe) == {"/shared/chatter"}
    assert set(nodes["driver"].publish) == {"/arm/joint/state"} and nodes["driver"].env == {"ARM": "1"}
    assert nodes["driver"].namespace == "/arm/joint"


def test_parameter_files_match_wildcards_and_names_and_lose_to_inline_values(tmp_path: Path) -> None:
    write(tmp_path, "params.yaml", """
/**:
  ros__parameters: {rate: 10, frame: map}
/left/ear:
  ros__parameters: {gain: {p: 2.0, i: 0.1}, frame: odom}
right:
  ros__parameters: {side: right}
""")
    project = load_project(write(tmp_path, "p.yaml", """
name: p
nodes:
  listener:
    run: case_nodes:listener
    parameter_files: [params.yaml]
    parameters: {rate: 20}
    instances:
      left: {namespace: /left, name: ear}
      right: {namespace: /right}
"""))
    left, right = project.model.nodes["left"].parameters, project.model.nodes["right"].parameters
    assert left == {"rate": 20, "frame": "odom", "gain.p": 2.0, "gain.i": 0.1}
    assert right == {"rate": 20, "frame": "map", "side": "right"}


def test_an_include_brings_its_nodes_under_a_namespace_with_its_arguments(tmp_path: Path) -> None:
    write(tmp_path, "station.yaml", """
name: station
args: {rate: 5, side: left}
targets: {here: {kind: process}, hardware: {kind: process}}
topics: {state: {history: keep_last, depth: 1}}
nodes:
  sensor: {run: case_nodes:talker, target: here, parameters: {rate: $(arg rate), side: $(arg side)},
           publish: {state: std_msgs/msg/String}}
  fuse: {run: case_nodes:listener, target: hardware, subscribe: {state: std_msgs/msg/String}}
""")
    project = load_project(write(tmp_path, "p.yaml", """
name: p
targets: {main: {kind: thread}}
include:
  one: {file: station.yaml, namespace: one, args: {rate: 50}, targets: {here: main}}
  two: {file: station.yaml, namespace: /two}
"""))
    nodes = project.model.nodes
    assert set(nodes) == {"one_sensor", "one_fuse", "two_sensor", "two_fuse"}
    assert nodes["one_sensor"].parameters == {"rate": 50, "side": "left"}
    assert nodes["two_sensor"].parameters == {"rate": 5, "side": "left"}
    assert nodes["one_sensor"].target == "main" and nodes["one_fuse"].target == "one_hardware"
    assert set(project.model.targets) == {"main", "one_hardware", "two_here", "two_hardware"}
    assert set(project.model.topics) == {"/one/state", "/two/state"}
    assert set(nodes["two_fuse"].subscribe) == {"/two/state"}


def test_planned_nodes_keep_their_namespace_remaps_and_environment(tmp_path: Path) -> None:
    (tmp_path / "case_nodes.py").write_text((Path(__file__).parents[1] / "cases" / "case_nodes.py").read_text())
    planned = plan(load_project(write(tmp_path, "p.yaml", """
name: p
nodes:
  talker: {run: case_nodes:talker, namespace: /robot, name: voice, remap: {chatter: /out}, env: {MODE: fast},
           publish: {chatter: std_msgs/msg/String}}
""")))
    node = planned.nodes["talker"]
    assert (node.namespace, node.ros_name, node.remap, node.env) == ("/robot", "voice", {"/robot/chatter": "/out"},
                                                                      {"MODE": "fast"})
    assert planned.env_of(planned.process_of("talker")) == {"MODE": "fast"}


@pytest.mark.parametrize(("text", "expected"), [
    ("name: p\nnodes:\n  a: {run: $(arg missing), target: main}\n",
     "p.yaml:3: $(arg missing): no such argument; declare it under args:"),
    ("name: p\nnodes:\n  a: {run: $(env HETROS_TEST_UNSET_VARIABLE), target: main}\n",
     "p.yaml:3: $(env HETROS_TEST_UNSET_VARIABLE): HETROS_TEST_UNSET_VARIABLE is not set"),
    ("name: p\ninclude:\n  again: {file: p.yaml}\n", "includes nest more than 16 deep"),
    ("name: p\nnodes:\n  a: {run: m:f}\n  b: {run: m:f, instances: {a: {}}}\n", "node 'a' is defined twice"),
    ("name: p\ngroups: {}\n", "p.yaml:1: the project has no nodes"),
])
def test_bad_conveniences_name_the_place(tmp_path: Path, text: str, expected: str) -> None:
    with pytest.raises(ProjectError, match=None) as info:
        load_project(write(tmp_path, "p.yaml", text))
    assert expected in str(info.value)


def test_nodes_sharing_a_process_must_agree_on_their_environment(tmp_path: Path) -> None:
    (tmp_path / "case_nodes.py").write_text((Path(__file__).parents[1] / "cases" / "case_nodes.py").read_text())
    report = check(load_project(write(tmp_path, "p.yaml", """
name: p
topics: {/chatter: {}}
nodes:
  talker: {run: case_nodes:talker, env: {MODE: fast}, publish: {/chatter: std_msgs/msg/String}}
  listener: {run: case_nodes:listener, env: {MODE: slow}, subscribe: {/chatter: std_msgs/msg/String}}
""")))
    assert any("MODE='slow', but node 'talker' in the same process asks MODE='fast'" in e for e in report.errors), \
        report.errors
