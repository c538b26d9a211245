"""Public ROS 2 Python launch files, unchanged (tests/data/ros2_launch, and the launch files inside the
ros2/demos packages), imported and launched: the graph each gives is the graph the file declares, and
`hetros launch FILE` runs it as `ros2 launch` does. The C++ packages they name are given as Python twins
(tests/data/cpp_twins)."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support.cli import hetros_in

DATA = Path(__file__).resolve().parents[1] / "data"
LAUNCH = DATA / "ros2_launch"
TWINS = DATA / "cpp_twins"
DEMOS = DATA / "ros2_demos"



def _imported(file: Path, tmp_path: Path, *args: str) -> dict[str, Any]:
    out = tmp_path / "project.yaml"
    done = hetros_in("import", "ros2launch", str(file), "--package-path", str(TWINS), "-o", str(out), *args,
                   cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    project: dict[str, Any] = yaml.safe_load(out.read_text())
    checked = hetros_in("check", str(out), cwd=tmp_path)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return project


def _graph(project: dict[str, Any]) -> dict[str, tuple[str, str, dict[str, str]]]:
    """node -> (its code, namespace, remaps)."""
    return {key: (node["run"], node.get("namespace", ""), node.get("remap", {}))
            for key, node in project["nodes"].items()}


@pytest.mark.parametrize(("file", "graph"), [
    ("demos/talker_listener_launch.py", {"talker": ("demo_nodes_py.topics.talker:main", "", {}),
                                         "listener": ("demo_nodes_py.topics.listener:main", "", {})}),
    ("demos/talker_listener_best_effort_launch.py",
     {"talker": ("demo_nodes_py.topics.talker:main", "", {}),  # a node without a launch name keeps its code's
      "listener": ("cpp_twins.listener_best_effort:main", "", {})}),
    ("demos/add_two_ints_async_launch.py",
     {"add_two_ints_server": ("demo_nodes_py.services.add_two_ints_server:main", "", {}),
      "add_two_ints_client": ("demo_nodes_py.services.add_two_ints_client_async:main", "", {})}),
    ("ros2launch/example.launch.py",
     {"robot_talker": ("demo_nodes_py.topics.talker:main", "", {}),
      "robot_listener": ("demo_nodes_py.topics.listener:main", "", {})}),
    ("ros2launch/includes_example.launch.py",
     {"FOOtalker": ("demo_nodes_py.topics.talker:main", "", {}),
      "FOOlistener": ("demo_nodes_py.topics.listener:main", "", {})}),
])
def test_a_public_launch_file_gives_the_graph_it_declares(file: str, graph: dict[str, Any], tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("USER", "robot")  # example.launch.py's node_prefix: $USER + '_'
    project = _imported(LAUNCH / file, tmp_path)
    assert _graph(project) == graph
    for key in graph:
        assert project["nodes"][key].get("name", key) == key


def test_the_python_xml_and_yaml_talker_listener_give_one_graph(tmp_path: Path) -> None:
    graphs = []
    for suffix in ("py", "xml", "yaml"):
        folder = tmp_path / suffix
        folder.mkdir()
        graphs.append(_graph(_imported(LAUNCH / "demos" / f"talker_listener_launch.{suffix}", folder)))
    assert graphs[0] == graphs[1] == graphs[2]


def test_an_exit_that_shuts_the_launch_down_makes_its_node_required(tmp_path: Path) -> None:
    project = _imported(LAUNCH / "demos" / "add_two_ints_launch.py", tmp_path)
    assert project["nodes"]["add_two_ints_client"].get("required") is True
    assert "required" not in project["nodes"]["add_two_ints_server"]
    # ros2 launch: the client's result, then the launch ends with the client, cleanly
    done = hetros_in("launch", str(LAUNCH / "demos" / "add_two_ints_launch.py"), "--package-path", str(TWINS),
                   cwd=tmp_path, timeout=90)
    assert done.returncode == 0, done.stderr
    assert re.search(r"\[add_two_ints_client\]: Result of add_two_ints: 5", done.stderr), done.stderr


def test_the_c_plus_plus_lifecycle_demos_launch_file(tmp_path: Path) -> None:
    """lifecycle's launch file: a LifecycleNode (managed, unconfigured), the listener, and the service client
    whose exit (on_exit=Shutdown()) ends the launch; nodes keep their code's names where it gives none."""
    project = _imported(LAUNCH / "demos" / "lifecycle_cpp_demo_launch.py", tmp_path)
    nodes = project["nodes"]
    assert sorted(nodes) == ["lc_client", "lc_listener", "lc_talker"]
    assert nodes["lc_talker"]["lifecycle"] == "unconfigured" and nodes["lc_talker"]["run"] == "lifecycle_py.talker:main"
    assert nodes["lc_client"].get("required") is True and "required" not in nodes["lc_listener"]
    assert nodes["lc_client"]["clients"] == {"/lc_talker/get_state": "lifecycle_msgs/srv/GetState",
                                             "/lc_talker/change_state": "lifecycle_msgs/srv/ChangeState"}


def test_hetros_launch_runs_a_python_launch_file_with_its_arguments(tmp_path: Path) -> None:
    done = hetros_in("launch", str(LAUNCH / "ros2launch" / "example.launch.py"), "node_prefix:=pre_",
                   "--package-path", str(TWINS), "--duration", "4", cwd=tmp_path, timeout=90)
    assert done.returncode == 0, done.stderr
    assert re.search(r"\[pre_talker\]: Publishing: \"Hello World: 1\"", done.stderr), done.stderr
    assert re.search(r"\[pre_listener\]: I heard: \[Hello World: 1\]", done.stderr), done.stderr


@pytest.mark.parametrize(("file", "line", "words"), [
    ("demos/dummy_robot_bringup_launch.py", 24, "package 'dummy_robot_bringup' not found"),
])
def test_what_a_public_launch_file_needs_beyond_python_is_refused_at_its_line(file: str, line: int, words: str,
                                                                             tmp_path: Path) -> None:
    done = hetros_in("import", "ros2launch", str(LAUNCH / file), "--package-path", str(TWINS), cwd=tmp_path)
    assert done.returncode != 0
    assert f"{LAUNCH / file}:{line}: " in done.stderr and words in done.stderr, done.stderr
    assert "Traceback" not in done.stderr


def test_a_containers_components_run_as_threads_of_one_process(tmp_path: Path) -> None:
    """composition's launch file: a ComposableNodeContainer with the Talker and Listener components, given
    by a Python package under the rclpy_components entry point group (tests/data/cpp_twins/composition)."""
    project = _imported(LAUNCH / "demos" / "composition_demo_launch.py", tmp_path)
    assert {key: (node["run"], node["target"]) for key, node in project["nodes"].items()} == {
        "talker": ("cpp_twins_composition.talker_component:Talker", "my_container"),
        "listener": ("cpp_twins_composition.listener_component:Listener", "my_container")}
    assert project["targets"] == {"my_container": {"kind": "process"}}
    done = hetros_in("launch", str(LAUNCH / "demos" / "composition_demo_launch.py"), "--package-path", str(TWINS),
                     "--duration", "4", cwd=tmp_path, timeout=90)
    assert done.returncode == 0, done.stderr
    assert re.search(r"\[talker\]: Publishing: 'Hello World: 1'", done.stderr), done.stderr
    assert re.search(r"\[listener\]: I heard: \[Hello World: 1\]", done.stderr), done.stderr


def test_a_component_no_package_offers_is_refused_at_its_line(tmp_path: Path) -> None:
    launch = tmp_path / "components_launch.py"
    launch.write_text(textwrap.dedent("""\
        from launch import LaunchDescription
        from launch_ros.actions import ComposableNodeContainer
        from launch_ros.descriptions import ComposableNode


        def generate_launch_description():
            return LaunchDescription([ComposableNodeContainer(
                name='c', namespace='', package='rclcpp_components', executable='component_container',
                composable_node_descriptions=[
                    ComposableNode(package='composition', plugin='composition::Server', name='server')])])
        """))
    done = hetros_in("import", "ros2launch", str(launch), "--package-path", str(TWINS), cwd=tmp_path)
    assert done.returncode != 0 and "Traceback" not in done.stderr
    assert f"{launch}:10: package composition offers no component 'composition::Server' (its rclpy_components: " \
           "composition::Listener, composition::Talker)" in done.stderr, done.stderr


def test_topic_monitors_launch_files_give_their_publishers(tmp_path: Path) -> None:
    """ExecuteProcess of ExecutableInPackage: the package's node, with the command line the file gives."""
    done = hetros_in("import", "ros2launch", str(DEMOS / "topic_monitor" / "launch" / "depth_demo_launch.py"), "-o",
                   str(tmp_path / "p.yaml"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    nodes = yaml.safe_load((tmp_path / "p.yaml").read_text())["nodes"]
    assert [node["args"] for node in nodes.values()] == [
        [f"{size}_depth_{depth}", "--depth", str(depth), "--payload-size", payload]
        for size, payload in (("small", "0"), ("large", "100000")) for depth in (1, 50)]
    assert {node["run"] for node in nodes.values()} == {"topic_monitor.scripts.data_publisher:main"}
