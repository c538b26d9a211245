"""rclpy nodes, unchanged, under `hetros launch` with the project `hetros init` writes for them: the
ros2/examples minimal publishers, subscribers, services, clients, action servers and clients and the
executors package (tests/data/ros2_examples, copied as they are), each node in a process of its own,
printing what they print under ROS 2."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import yaml

RCLPY = Path(__file__).resolve().parents[1] / "data" / "ros2_examples" / "rclpy"
PACKAGES = [RCLPY / "topics" / "minimal_publisher", RCLPY / "topics" / "minimal_subscriber",
            RCLPY / "services" / "minimal_service", RCLPY / "services" / "minimal_client",
            RCLPY / "actions" / "minimal_action_server", RCLPY / "actions" / "minimal_action_client",
            RCLPY / "executors"]


def init(tmp_path: Path, *sources: Path) -> dict[str, Any]:
    """The project `hetros init` writes for ``sources`` (files or package folders)."""
    project = tmp_path / "project.yaml"
    made = subprocess.run([sys.executable, "-m", "hetros", "init", *map(str, sources), "-o", str(project),
                           "--name", "rclpy_examples"], capture_output=True, text=True, timeout=60, check=False)
    assert made.returncode == 0, made.stderr
    data: dict[str, Any] = yaml.safe_load(project.read_text())
    return data


def launch(tmp_path: Path, project: dict[str, Any], duration: float) -> subprocess.CompletedProcess[str]:
    """Check, then launch, ``project``: the packages' code is found through the python_path: that init
    wrote (the environment's PYTHONPATH is left as it is)."""
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    checked = subprocess.run([sys.executable, "-m", "hetros", "check", str(path)], capture_output=True,
                             text=True, timeout=120, check=False)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    return subprocess.run([sys.executable, "-m", "hetros", "launch", str(path), "--duration", str(duration)],
                          capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)


def module(package: str, name: str) -> Path:
    folder = next(p for p in PACKAGES if (p / package).is_dir())
    return folder / package / f"{name}.py"


def keyed(project: dict[str, Any], entry: str) -> str:
    """The key `hetros init` gave the node whose run: is ``entry``'s main."""
    return next(k for k, n in project["nodes"].items() if n["run"].endswith(f".{entry}:main"))


def test_the_minimal_publishers_and_subscribers(tmp_path: Path) -> None:
    """Every publisher and subscriber variant at once, each pair in a namespace; one pair as threads of the
    launching process, the others each node in a process of its own."""
    project = init(tmp_path, RCLPY / "topics" / "minimal_publisher", RCLPY / "topics" / "minimal_subscriber")
    # create_publisher(String, 'topic', 10)
    assert project["topics"] == {"/topic": {"history": "keep_last", "depth": 10}}
    assert len(project["nodes"]) == 6
    project["topics"] = {}
    project["targets"]["main"] = {"kind": "thread"}
    pairs = {"members": ("publisher_member_function", "subscriber_member_function"),
             "old": ("publisher_old_school", "subscriber_old_school"),
             "threads": ("publisher_local_function", "subscriber_lambda")}
    for namespace, entries in pairs.items():
        for entry in entries:
            node = project["nodes"][keyed(project, entry)]
            node["namespace"] = namespace
            if namespace == "threads":
                node["target"] = "main"
        project["topics"][f"/{namespace}/topic"] = {"history": "keep_last", "depth": 10}
    done = launch(tmp_path, project, 2.4)
    assert done.returncode == 0, done.stderr
    for namespace in pairs:
        published = re.findall(rf"\[{namespace}\.minimal_publisher\]: (.*)", done.stderr)
        heard = re.findall(rf"\[{namespace}\.minimal_subscriber\]: (.*)", done.stderr)
        assert published[:3] == [f'Publishing: "Hello World: {i}"' for i in range(3)], done.stderr
        assert heard[:3] == [f'I heard: "Hello World: {i}"' for i in range(3)], done.stderr
    assert "Traceback" not in done.stderr


def test_the_minimal_services_and_clients(tmp_path: Path) -> None:
    """Every client variant at once, each with a server in its namespace."""
    project = init(tmp_path, RCLPY / "services" / "minimal_service", RCLPY / "services" / "minimal_client")
    server = keyed(project, "service")
    assert project["nodes"][server]["services"] == {"add_two_ints": "example_interfaces/srv/AddTwoInts"}
    pairs = {"plain": ("service", "client", "minimal_client"),
             "future": ("service_member_function", "client_async", "minimal_client_async"),
             "member": ("service", "client_async_member_function", "minimal_client_async"),
             "callback": ("service_member_function", "client_async_callback", "minimal_client")}
    nodes = dict(project["nodes"])
    project["nodes"] = {}
    for namespace, (service, client, _) in pairs.items():
        for entry in (service, client):
            node = dict(nodes[keyed({"nodes": nodes}, entry)], namespace=namespace)
            project["nodes"][f"{namespace}_{entry}"] = node
    project["targets"] = {key: {"kind": "process"} for key in project["nodes"]}
    for key, node in project["nodes"].items():
        node["target"] = key
    done = launch(tmp_path, project, 5)
    assert done.returncode == 0, done.stderr
    for namespace, (_, _, client_name) in pairs.items():
        assert f"[{namespace}.minimal_service]: Incoming request\na: 41 b: 1\n" in done.stderr
        assert f"[{namespace}.{client_name}]: Result of add_two_ints: for 41 + 1 = 42\n" in done.stderr
    assert "Traceback" not in done.stderr


ACTION = "example_interfaces/action/Fibonacci"
FIBONACCI = "array('i', [0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55])"


def test_the_minimal_action_servers_and_clients(tmp_path: Path) -> None:
    """Six server/client pairs at once, each pair in a namespace of its own (their code names the same
    action, 'fibonacci'): results, feedback, deferred execution, cancel, an asyncio client's two goals at once
    against the server that keeps one goal (the first aborted) and the one that queues them, printed as ROS 2
    prints them."""
    pairs = {"plain": ("server", "client"), "deferred": ("server_defer", "client"),
             "functions": ("server_not_composable", "client_not_composable"), "cancel": ("server", "client_cancel"),
             "single": ("server_single_goal", "client_asyncio"), "queued": ("server_queue_goals", "client_asyncio")}
    project = init(tmp_path, *(module("examples_rclpy_minimal_action_server", server) for server, _ in pairs.values()),
                   *(module("examples_rclpy_minimal_action_client", client) for _, client in pairs.values()))
    # keyed by their entry points (all four servers name their node the same), in the order given
    servers = [k for k, n in project["nodes"].items() if "minimal_action_server." in n["run"]]
    clients = [k for k, n in project["nodes"].items() if "minimal_action_client." in n["run"]]
    assert servers == ["server", "server_defer", "server_not_composable", "server_2", "server_single_goal",
                       "server_queue_goals"], servers
    assert len(servers) == len(clients) == 6
    for node in project["nodes"].values():
        assert node.get("actions", node.get("action_clients")) == {"fibonacci": ACTION}
    for namespace, server, client in zip(pairs, servers, clients, strict=True):
        project["nodes"][server]["namespace"] = project["nodes"][client]["namespace"] = namespace
    done = launch(tmp_path, project, 17.0)
    assert done.returncode == 0, done.stderr
    out = done.stderr
    for namespace in ("plain", "deferred", "functions"):
        assert f"[{namespace}.minimal_action_client]: Goal accepted :)" in out, out
        assert f"[{namespace}.minimal_action_client]: Goal succeeded! Result: {FIBONACCI}" in out, out
        assert f"[{namespace}.minimal_action_server]: Returning result: {FIBONACCI}" in out, out
    feedback = re.findall(r"\[plain\.minimal_action_client\]: Received feedback: (.*)", out)
    assert feedback == [f"array('i', {[0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55][:n]})" for n in range(3, 12)], out
    assert "[deferred.minimal_action_server]: Deferring execution..." in out
    assert "[cancel.minimal_action_server]: Received cancel request" in out
    assert "[cancel.minimal_action_client]: Goal successfully canceled" in out
    assert "[cancel.minimal_action_server]: Goal canceled" in out
    # client_asyncio sends two goals at once from an asyncio loop: the single-goal server aborts the first
    assert "[single.minimal_action_server]: Aborting previous goal" in out, out
    assert "[single.minimal_action_client_asyncio]: Goal failed with status: 6" in out, out
    assert f"[single.minimal_action_client_asyncio]: Goal succeeded! Result: {FIBONACCI}" in out, out
    assert "[minimal_action_client]: unfinished: 0" in out, out
    # printed as rclpy prints a message: its module path, numeric sequences as lists
    assert f"[minimal_action_client]: result example_interfaces.action.Fibonacci_Result(sequence=" \
           f"{[0, 1, 1, 2, 3, 5, 8, 13, 21, 34, 55]}) and status flag 4" in out, out
    assert "[minimal_action_client]: result example_interfaces.action.Fibonacci_Result(sequence=[]) and status " \
           "flag 6" in out, out
    # and the queueing server takes the second when the first is done
    assert "[queued.minimal_action_server]: Goal put in the queue" in out, out
    assert f"[queued.minimal_action_client_asyncio]: Goal succeeded! Result: {FIBONACCI}" in out, out
    assert "Traceback" not in out


EXECUTORS = RCLPY / "executors"


def test_the_executors_examples(tmp_path: Path) -> None:
    """ros2/examples' executors package: talker and listener in two processes, and in one process each the
    composed nodes, a callback group, a custom (token-bucket) callback group and a custom executor."""
    project = init(tmp_path, EXECUTORS)
    assert set(project["nodes"]) == {"talker", "listener", "composed", "callback_group", "intermittent_talker",
                                     "custom_executor"}
    assert project["nodes"]["custom_executor"]["subscribe"] == {"chatter": "std_msgs/msg/String",
                                                                "estop": "std_msgs/msg/String"}
    namespaces = {"talker": "apart", "listener": "apart", "composed": "composed", "callback_group": "grouped",
                  "intermittent_talker": "throttled", "custom_executor": "prioritised"}
    for key, namespace in namespaces.items():
        project["nodes"][key]["namespace"] = namespace
    project["topics"] = {"/throttled/chatter": {"history": "keep_last", "depth": 10}}
    (tmp_path / "estop.py").write_text(  # what `ros2 topic pub /estop` would be, as a node
        "from std_msgs.msg import String\n\n"
        "def estop(node):\n"
        "    publisher = node.create_publisher(String, 'estop')\n"
        "    node.create_timer(1.0, lambda: publisher.publish(String(data='STOP')))\n")
    project["nodes"]["estop"] = {"run": "estop:estop", "target": "talker", "namespace": "prioritised",
                                 "publish": {"estop": "std_msgs/msg/String"}}
    done = launch(tmp_path, project, 3.6)
    assert done.returncode == 0, done.stderr
    out = done.stderr
    for namespace in ("apart", "composed", "prioritised"):
        assert f'[{namespace}.talker]: Publishing: "Hello World: 2"' in out, out
        assert f'[{namespace}.listener]: I heard: "Hello World: 2"' in out, out
    assert '[grouped.double_talker]: Publishing: "Hello World: 5"' in out  # two timers: 1 s and 0.5 s
    assert '[grouped.listener]: I heard: "Hello World: 5"' in out
    assert '[prioritised.estopper]: I heard: "STOP"' in out
    throttled = re.findall(r"\[throttled\.intermittent_talker\]: Publishing: \"Hello World: (\d+)\"", out)
    assert 13 <= len(throttled) <= 18, throttled  # a bucket of 10 at 10 Hz, then a token every 0.5 s
    assert "Traceback" not in out


def test_hetros_action_send_goal_reaches_an_unchanged_rclpy_server_and_prints_feedback(tmp_path: Path) -> None:
    """`hetros action send_goal -f` against ros2/examples' minimal action server, as `ros2 action send_goal
    -f` is used: each feedback, then the result."""
    import json
    import time

    project = init(tmp_path, module("examples_rclpy_minimal_action_server", "server"))
    path = tmp_path / "project.yaml"
    path.write_text(yaml.safe_dump(project))
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(path), "--duration", "60"], env=env,
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, cwd=tmp_path) as launched:
        try:
            deadline = time.monotonic() + 60
            while time.monotonic() < deadline:
                top = subprocess.run([sys.executable, "-m", "hetros", "top", "--json", "--once"], env=env,
                                     capture_output=True, text=True, timeout=60, check=False)
                if top.returncode == 0 and not json.loads(top.stdout)["silent"]:
                    break
                time.sleep(0.3)
            done = subprocess.run([sys.executable, "-m", "hetros", "action", "send_goal", "-f", "/fibonacci",
                                   ACTION, "{order: 3}"], env=env, capture_output=True, text=True, timeout=60,
                                  check=False)
        finally:
            launched.terminate()
            launched.wait(30)
    assert done.returncode == 0, done.stdout + done.stderr
    out = done.stdout
    assert re.search(r"Goal accepted with ID: [0-9a-f]{32}\n", out), out
    assert out.count("Feedback:\n    sequence:\n") == 2, out
    assert out.index("Feedback:") < out.index("Result:") and out.rstrip().endswith(
        "Goal finished with status: SUCCEEDED"), out
