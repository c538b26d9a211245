"""Public ROS examples, unchanged, under `hetros init` / `hetros import` and `hetros launch`: the Python
packages of ros2/demos (tests/data/ros2_demos) and rospy tutorials with their own launch files
(tests/data/ros_tutorials), each node in a process of its own, printing what they print under ROS
(time stamps aside). The ros2/examples rclpy packages and the other rospy tutorials have their own
tests (test_rclpy.py, test_rospy.py)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import yaml

DATA = Path(__file__).resolve().parents[1] / "data"
DEMOS = DATA / "ros2_demos"
TUTORIALS = DATA / "ros_tutorials"


def _hetros(*argv: str, cwd: Path | None = None, timeout: float = 60,
            env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "hetros", *argv], capture_output=True, text=True, timeout=timeout,
                          check=False, cwd=cwd, env=env)


def _demos_project(tmp_path: Path) -> dict[str, Any]:
    """`hetros init` of the three packages, then the choice a user makes: which nodes, in which namespace
    (two demos serve add_two_ints), with which command line."""
    made = _hetros("init", str(DEMOS / "demo_nodes_py"), str(DEMOS / "action_tutorials_py"),
                   str(DEMOS / "quality_of_service_demo_py"), "-o", str(tmp_path / "all.yaml"), "--name", "demos")
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "all.yaml").read_text())
    chosen = {"talker": "", "listener": "", "serialized_subscriber": "", "talker_qos": "qos", "listener_qos": "qos",
              "add_two_ints_server": "", "add_two_ints_client": "", "add_two_ints_client_async": "",
              "introspection": "intro", "set_parameters_callback": "", "fibonacci_action_server": "",
              "fibonacci_action_client": "", "qos_overrides_talker": "", "qos_overrides_listener": "",
              "deadline": "dl", "matched_event_detect": "", "use_logger_service": "",
              "incompatible_qos": "iq", "lifespan": "ls", "liveliness": "lv"}
    nodes = {key: node for key, node in project["nodes"].items() if key in chosen}
    assert sorted(nodes) == sorted(chosen), sorted(project["nodes"])
    for key, namespace in chosen.items():
        if namespace:
            nodes[key]["namespace"] = namespace
    nodes["talker_qos"]["args"] = ["--reliable", "-n", "4"]
    nodes["listener_qos"]["args"] = ["--reliable", "-n", "4"]
    nodes["deadline"]["args"] = ["600", "--publish-for", "2000", "--pause-for", "2000"]
    nodes["incompatible_qos"]["args"] = ["reliability"]
    nodes["lifespan"]["args"] = ["1000", "--subscribe-after", "2750"]
    nodes["liveliness"]["args"] = ["1000"]
    project["nodes"] = nodes
    project["targets"] = {node["target"]: {"kind": "process"} for node in nodes.values()}
    project["topics"] = {"/chatter": {"history": "keep_last", "depth": 10},
                         "/qos/chatter": {"history": "keep_last", "depth": 10},
                         "/qos_overrides_chatter": {"history": "keep_last", "depth": 10}}
    # lifespan's topic has no QoS here: its endpoints keep what the code asks (transient_local, 1 s)
    return project


def test_the_ros2_demos_python_packages(tmp_path: Path) -> None:
    project = _demos_project(tmp_path)
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    checked = _hetros("check", str(path))
    assert checked.returncode == 0, checked.stdout + checked.stderr
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))  # this launch alone, whatever else runs
    launched = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(path), "--duration", "14"],
                                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        # ros2 param set /set_parameters_callback param1 10.0: its pre-set callback sets param2 to 4.0
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and _hetros("param", "get", "/set_parameters_callback", "param1",
                                                      env=env).returncode != 0:
            time.sleep(0.3)
        assert _hetros("param", "set", "/set_parameters_callback", "param1", "10.0", env=env).returncode == 0
        got = _hetros("param", "get", "/set_parameters_callback", "param2", env=env)
        assert got.stdout.strip() == "Double value is: 4.0", got.stdout + got.stderr
        refused = _hetros("param", "set", "/set_parameters_callback", "param3", "1", env=env)
        assert refused.returncode != 0
        _, err = launched.communicate(timeout=90)
    finally:
        launched.kill()
    assert launched.returncode == 0, err
    lines = err.splitlines()

    def said(node: str) -> list[str]:
        """What ``node`` logged, in ROS 2's console form ``[INFO] [sec.nsec] [node]: text``."""
        form = re.compile(rf"^\[INFO\] \[\d+\.\d{{9}}\] \[{re.escape(node)}\]: (.*)$")
        return [m.group(1) for line in lines if (m := form.match(line))]

    hello = [line for line in said("talker") if line.startswith("Publishing")]
    assert hello[:3] == [f'Publishing: "Hello World: {i}"' for i in range(3)], err
    assert [line for line in said("listener") if line.startswith("I heard")][:3] == \
        [f"I heard: [Hello World: {i}]" for i in range(3)], err
    # listener_serialized: raw=True hands the callback the CDR bytes
    assert said("serialized_subscriber")[0] == \
        "I heard: \"b'\\x00\\x01\\x00\\x00\\x0f\\x00\\x00\\x00Hello World: 0\\x00'\"", err
    # talker_qos/listener_qos --reliable -n 4: argparse on each node's own command line
    assert said("qos.talker_qos")[:5] == ["Reliable talker", *(f'Publishing: "Hello World: {i}"' for i in range(4))]
    assert said("qos.listener_qos")[0] == "Reliable listener"
    assert said("qos.listener_qos")[1:] == [f"I heard: [Hello World: {i}]" for i in range(len(said("qos.listener_qos"))
                                                                                           - 1)], err
    assert len(said("qos.listener_qos")) >= 3, err
    assert said("add_two_ints_client").count("Result of add_two_ints: 5") == 2, err  # the client and the async one
    assert said("add_two_ints_server").count("Incoming request") == 2, err
    assert "Result of add_two_ints: 5" in said("intro.introspection_client"), err
    assert said("fibonacci_action_client")[:2] == ["Goal accepted :)", "Received feedback: array('i', [0, 1, 1])"]
    assert "Result: array('i', [0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55])" in said("fibonacci_action_client"), err
    assert said("qos_overrides_talker")[0] == 'Publishing: "Hello World: 0"', err
    assert said("qos_overrides_listener")[0] == "I heard: [Hello World: 0]", err
    # deadline 600: the QoS the code asks for (the project file sets none for the topic) is watched on both
    # ends while the talker pauses for 2 s (the demo logs them through get_logger('talker') and ('listener'))
    assert "Offered deadline missed - total 1 delta 1" in said("talker"), err
    assert "Requested deadline missed - total 1 delta 1" in said("listener"), err
    assert "Publishing: 'Talker says 4'" in said("dl.talker"), err
    # matched_event_detect: three rclpy nodes of one process create and destroy endpoints
    assert said("matched_event_detection_node") == [
        "First subscription is connected.",
        "The changed number of connected subscription is 1 and current number of connected subscription is 2",
        "The changed number of connected subscription is -1 and current number of connected subscription is 1",
        "Last subscription is disconnected.",
        "First publisher is connected.",
        "The changed number of connected publisher is 1 and current number of connected publisher is 2",
        "The changed number of connected publisher is -1 and current number of connected publisher is 1",
        "Last publisher is disconnected."], err
    # incompatible_qos reliability: a best_effort talker and a reliable listener of one process do not match
    # (the demo logs through get_logger('talker') and ('listener')); the listener hears nothing
    kind = "last_policy_kind: rmw_qos_policy_kind_t.RMW_QOS_POLICY_RELIABILITY"
    assert f"Offered incompatible qos - total 1 delta 1 {kind}" in said("talker"), err
    assert f"Requested incompatible qos - total 1 delta 1 {kind}" in said("listener"), err
    assert "Publishing: 'Talker says 4'" in said("iq.talker"), err
    assert said("iq.listener") == ["Listener starting up"], err
    # lifespan 1000, subscribing after 2.75 s: the late listener gets the stored messages younger than 1 s
    late = [f"Listener heard: [Talker says {i}]" for i in range(3, 10)]
    assert said("ls.listener") == ["Listener starting up", *late], err
    # liveliness 1000 (automatic): the listener hears the talker come, and go when its node is destroyed
    # after 3 s (the demo logs through get_logger('listener'))
    events = [line for line in said("listener") if line.startswith(("Liveliness changed", "  "))]
    assert events == ["Liveliness changed event:", "  alive_count: 1", "  not_alive_count: 0",
                      "  alive_count_change: 1", "  not_alive_count_change: 0",
                      "Liveliness changed event:", "  alive_count: 0", "  not_alive_count: 0",
                      "  alive_count_change: -1", "  not_alive_count_change: 0"], err
    heard = [line for line in said("lv.listener") if line.startswith("Listener heard")]
    assert 4 <= len(heard) <= 7 and heard[0] == "Listener heard: [Talker says 0]", err
    # use_logger_service: one node sets another's logger level through its logger service
    levels = re.findall(r"^\[(\w+)\] \[\d+\.\d{9}\] \[LoggerServiceNode\]: Output (\d) with \w+ logger level\.$",
                        err, re.MULTILINE)
    assert levels == [("INFO", "1"), ("WARN", "1"), ("ERROR", "1"), ("DEBUG", "2"), ("INFO", "2"), ("WARN", "2"),
                      ("ERROR", "2"), ("WARN", "3"), ("ERROR", "3"), ("ERROR", "4")], err
    assert [line for line in said("TestNode") if line.startswith("Current")] == \
        [f"Current logger level: {level}" for level in (0, 10, 30, 40)], err
    assert "Traceback" not in err, err


# demo_nodes_cpp's parameter_blackboard, which the async_param_client demo talks to, is C++: this is it in
# rclpy (a node that takes any parameter)
_BLACKBOARD = """\
import rclpy
from rclpy.node import Node


def main():
    rclpy.init()
    node = Node('parameter_blackboard', allow_undeclared_parameters=True,
                automatically_declare_parameters_from_overrides=True)
    rclpy.spin(node)
"""


def test_async_param_client_against_a_parameter_blackboard(tmp_path: Path) -> None:
    """demo_nodes_py's async_param_client, unchanged: rclpy.parameter_client over the blackboard's parameter
    services (planned by `hetros init` from the code), ament_index_python for its parameter file."""
    (tmp_path / "parameter_blackboard.py").write_text(_BLACKBOARD)
    made = _hetros("init", str(DEMOS / "demo_nodes_py"), str(tmp_path / "parameter_blackboard.py"), "-o",
                   str(tmp_path / "all.yaml"), "--name", "params", cwd=tmp_path)
    assert made.returncode == 0, made.stderr
    project: dict[str, Any] = yaml.safe_load((tmp_path / "all.yaml").read_text())
    project["nodes"] = {k: v for k, v in project["nodes"].items() if k in ("async_param_client",
                                                                         "parameter_blackboard")}
    assert sorted(project["nodes"]["async_param_client"]["clients"]) == [
        f"parameter_blackboard/{s}" for s in ("describe_parameters", "get_parameter_types", "get_parameters",
                                              "list_parameters", "set_parameters", "set_parameters_atomically")]
    project["targets"] = {node["target"]: {"kind": "process"} for node in project["nodes"].values()}
    project.pop("topics", None)
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    checked = _hetros("check", str(path))
    assert checked.returncode == 0, checked.stdout + checked.stderr
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    launched = _hetros("launch", str(path), "--duration", "8", cwd=tmp_path, env=env)
    said = re.findall(r"^\[INFO\] \[\d+\.\d{9}\] \[async_param_client\]: (.*)$", launched.stderr, re.MULTILINE)
    assert said == [
        "Setting parameters:", "    int_parameter:", "        successful: True", "    bool_parameter:",
        "        successful: True", "    string_parameter:", "        successful: True",
        "Listing Parameters:", "    - int_parameter", "    - bool_parameter", "    - string_parameter",
        "Getting parameters:", "    - int_parameter: 10", "    - bool_parameter: False",
        "    - string_parameter: Fee Fi Fo Fum",
        "Loading parameters: ",
        "    other_int_parameter:", "        successful: True", "        value: 0",
        "    int_parameter:", "        successful: True", "        value: 12",
        "    string_parameter:", "        successful: True", "        value: I smell the blood of an Englishman",
        "    other_string_parameter:", "        successful: True",
        "        value: One fish, two fish, Red fish, blue fish",
        "    bool_parameter:", "        successful: True", "        value: False",
        "Deleting parameters: ",
        "    other_int_parameter:", "        successful: True", "        reason: ",
        "    other_string_parameter:", "        successful: True", "        reason: ",
        "    string_parameter:", "        successful: True", "        reason: "], launched.stderr
    assert "Traceback" not in launched.stderr and not list(tmp_path.glob("hetros-share-*")), launched.stderr


def test_rospy_tutorials_from_their_launch_files(tmp_path: Path) -> None:
    """002_headers (header.seq, stamp.to_sec()), 006_parameters (parameters in nested groups, a topic
    named by a private parameter, get_param of a namespace) and 010_publish_pointcloud2
    (sensor_msgs.point_cloud2, header.stamp = rospy.Time.now()), imported from their .launch files and
    started together (a project including them)."""
    for name, launch in (("headers", "002_headers/headers.launch"), ("params", "006_parameters/param_talker.launch"),
                         ("clouds", "010_publish_pointcloud2/publish_pointcloud2.launch")):
        imported = _hetros("import", "roslaunch", str(TUTORIALS / "rospy_tutorials" / launch), "--package-path",
                           str(TUTORIALS), "-o", str(tmp_path / f"{name}.yaml"))
        assert imported.returncode == 0, imported.stderr
    (tmp_path / "project.yaml").write_text("name: tutorials\ntargets: {main: {kind: thread}}\n"
                                           "include:\n  headers: {file: headers.yaml}\n"
                                           "  params: {file: params.yaml}\n  clouds: {file: clouds.yaml}\n")
    checked = _hetros("check", str(tmp_path / "project.yaml"))
    assert checked.returncode == 0, checked.stdout + checked.stderr
    done = _hetros("launch", str(tmp_path / "project.yaml"), "--duration", "2.5", cwd=tmp_path, timeout=90)
    assert done.returncode == 0, done.stderr
    # the launch file names the node: rospy's anonymous suffix gives way to it, as under roslaunch
    heard = re.findall(r"^/listener_header (\d+) I just heard that hello world (\d+) at +([\d.]+)$",
                       done.stdout, re.MULTILINE)
    assert len(heard) >= 5, done.stdout
    assert [(int(seq), int(count)) for seq, count, _ in heard[:5]] == [(i + 1, i) for i in range(5)]
    assert all(stamp == "0.000000" for _, _, stamp in heard)  # rospy leaves a None header's stamp at zero
    logged = re.findall(r"^\[INFO\] \[\d+\.\d{6}\]: (.*)$", done.stderr, re.MULTILINE)
    assert logged[:5] == ["/global_example is global value", "/foo/utterance is Hello World",
                          "/foo/param_talker/topic_name is chatter", "/foo/default_param is default_value",
                          "gains are 1.0, 2.0, 3.0"], done.stderr
    assert "deleted /foo/to_delete parameter" in logged and logged.count("Hello World") >= 2, done.stderr
    # the launch file's global <param> is the parameter server's /global_example, not the node's private one
    assert "found global_example parameter under key: /global_example" in logged, done.stderr
    params = yaml.safe_load((tmp_path / "params.yaml").read_text())
    assert params["parameters"]["/global_example"] == "global value"
    assert params["nodes"]["param_talker"]["parameters"] == {"topic_name": "chatter"}
    assert "Traceback" not in done.stderr, done.stderr  # the point cloud publisher ran until the end


def test_rospy_tutorials_003_remaps_each_talker_as_its_launch_file_says(tmp_path: Path) -> None:
    """listener_with_user_data.launch: `args="chatter:=chatterN"` remaps each talker, so the listener hears
    only chatter2's (its chatter subscriptions hear nobody), as under ROS 1."""
    launch = TUTORIALS / "rospy_tutorials" / "003_listener_with_user_data" / "listener_with_user_data.launch"
    done = _hetros("launch", str(launch), "--package-path", str(TUTORIALS), "--duration", "3", cwd=tmp_path,
                   timeout=90)
    assert done.returncode == 0, done.stderr
    heard = [line for line in done.stdout.splitlines() if "I heard" in line]
    assert len(heard) >= 5, done.stdout
    assert all(re.fullmatch(r"I heard \[hello world [\d.]+\] with userdata \[This is from chatter2\]", line)
               for line in heard), done.stdout
