"""Looking inside running launches from another terminal: ``hetros topic|node|service|param|top``
against the examples, across processes, on shared-memory, in-process and hardware topics; two
launches at once never mix; another user is refused."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import subprocess
import sys
import textwrap
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import yaml

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@contextlib.contextmanager
def running(project: Path, env: dict[str, str], log: Path, duration: float = 60.0) -> Iterator[subprocess.Popen[str]]:
    """``hetros launch project`` in the background until every process answers looks."""
    with log.open("w") as out, subprocess.Popen(
            [sys.executable, "-m", "hetros", "launch", str(project), "--duration", str(duration)],
            stdout=out, stderr=subprocess.STDOUT, text=True, env=env, cwd=log.parent) as proc:
        try:
            deadline = time.monotonic() + 90
            while time.monotonic() < deadline:
                assert proc.poll() is None, log.read_text()
                done = hetros(env, "top", "--json", "--once", "--interval", "0.1", "--project", str(project),
                              check=False)
                if done.returncode == 0 and not json.loads(done.stdout)["silent"]:
                    break
                time.sleep(0.3)
            else:
                pytest.fail(f"the launch never answered: {log.read_text()}")
            yield proc
        finally:
            proc.terminate()
            proc.wait(30)


def hetros(env: dict[str, str], *args: str, check: bool = True,
           timeout: float = 60) -> subprocess.CompletedProcess[str]:
    done = subprocess.run([sys.executable, "-m", "hetros", *args], capture_output=True, text=True, env=env,
                          timeout=timeout, check=False)
    if check:
        assert done.returncode == 0, f"hetros {' '.join(args)}:\n{done.stdout}\n{done.stderr}"
    return done


def _last_figures(text: str, pattern: str) -> list[float]:
    found = re.findall(pattern, text)
    assert found, text
    return [float(v) for v in found[-1]] if isinstance(found[-1], tuple) else [float(found[-1])]


@pytest.fixture
def env(tmp_path: Path) -> dict[str, str]:
    """A registry of launches of this test's own (other tests' launches are not listed)."""
    folder = tmp_path / "runtime"
    folder.mkdir()
    return dict(os.environ, XDG_RUNTIME_DIR=str(folder))


def test_talker_listener_across_processes(tmp_path: Path, env: dict[str, str]) -> None:
    project = EXAMPLES / "talker_listener" / "project.yaml"
    log = tmp_path / "launch.log"
    with running(project, env, log):
        assert hetros(env, "topic", "list").stdout == "/chatter\n"
        assert hetros(env, "topic", "list", "-t").stdout == "/chatter [std_msgs/msg/String]\n"
        assert hetros(env, "topic", "info", "/chatter").stdout == (
            "Type: std_msgs/msg/String\nPublisher count: 1\nSubscription count: 2\n")
        verbose = hetros(env, "topic", "info", "/chatter", "-v").stdout
        assert "Node name: listener2" in verbose and "Transports: shm" in verbose and "KEEP_ALL (10)" in verbose
        echoed = hetros(env, "topic", "echo", "/chatter", "--once").stdout
        assert re.fullmatch(r"data: hello world \d+\n---\n", echoed), echoed
        fields = hetros(env, "topic", "echo", "/chatter", "-n", "2", "--field", "data").stdout.split("---\n")
        assert len(fields) == 3 and all(re.fullmatch(r"hello world \d+\n", f) for f in fields[:2]), fields
        rate = _last_figures(hetros(env, "topic", "hz", "/chatter", "--duration", "2.2").stdout,
                             r"average rate: ([\d.]+)")[0]
        assert rate == pytest.approx(10.0, rel=0.05)
        bandwidth = hetros(env, "topic", "bw", "/chatter", "--duration", "3.2").stdout
        assert bandwidth.startswith("Subscribed to [/chatter]\n")
        per_second, size = _last_figures(bandwidth, r"(\d+) B/s from \d+ messages\n\tMessage size mean: (\d+) B")
        assert per_second == pytest.approx(10.0 * size, rel=0.10)
        assert hetros(env, "node", "list").stdout == "/listener\n/listener2\n/talker\n"
        parameter_services = "".join(f"    /talker/{name}: rcl_interfaces/srv/{kind}\n" for name, kind in (
            ("describe_parameters", "DescribeParameters"), ("get_parameter_types", "GetParameterTypes"),
            ("get_parameters", "GetParameters"), ("list_parameters", "ListParameters"),
            ("set_parameters", "SetParameters"), ("set_parameters_atomically", "SetParametersAtomically")))
        assert hetros(env, "node", "info", "/talker").stdout == (
            "/talker\n  Subscribers:\n  Publishers:\n    /chatter: std_msgs/msg/String\n  Service Servers:\n"
            f"{parameter_services}  Service Clients:\n  Action Servers:\n  Action Clients:\n")
        assert hetros(env, "service", "type", "/talker/get_parameters").stdout == "rcl_interfaces/srv/GetParameters\n"
        assert hetros(env, "service", "find", "rcl_interfaces/srv/SetParameters").stdout == \
            "/listener/set_parameters\n/listener2/set_parameters\n/talker/set_parameters\n"
        assert hetros(env, "param", "get", "/talker", "hz").stdout == "Double value is: 10.0\n"
        assert hetros(env, "param", "set", "/talker", "hz", "12").stdout == "Set parameter successful\n"
        assert hetros(env, "param", "get", "/talker", "hz").stdout == "Double value is: 12.0\n"
        refused = hetros(env, "param", "set", "/talker", "hz", "fast", check=False)
        assert refused.returncode == 1 and "is a float, not a str" in refused.stdout
        assert hetros(env, "param", "list", "/talker").stdout == "/talker:\n  hz\n"
        assert yaml.safe_load(hetros(env, "param", "dump", "/talker").stdout) == \
            {"/talker": {"ros__parameters": {"hz": 12.0}}}
        (tmp_path / "params.yaml").write_text("/talker:\n  ros__parameters:\n    hz: 11.0\n")
        assert hetros(env, "param", "load", "/talker", str(tmp_path / "params.yaml")).stdout == \
            "Set parameter hz successful\n"
        assert hetros(env, "param", "get", "/talker", "hz").stdout == "Double value is: 11.0\n"
        assert hetros(env, "topic", "type", "/chatter").stdout == "std_msgs/msg/String\n"
        assert hetros(env, "topic", "find", "std_msgs/msg/String").stdout == "/chatter\n"
        assert hetros(env, "topic", "find", "std_msgs/msg/Int32").stdout == ""
        logged = hetros(env, "log", "--node", "listener2").stdout.splitlines()
        stamps = [float(re.match(r"\[INFO\] \[([\d.]+)\] \[listener2\]: I heard: \[hello world \d+\]$", line)[1])
                  for line in logged]
        assert len(stamps) >= 10 and stamps == sorted(stamps)
        published = hetros(env, "topic", "pub", "/chatter", "std_msgs/msg/String", "{data: from the command line}",
                           "--once").stdout
        assert "publishing #1: std_msgs.msg.String(data='from the command line')" in published
        top = json.loads(hetros(env, "top", "--json", "--once", "--interval", "1.5").stdout)
        assert {p["process"] for p in top["processes"]} == {"cluster1", "cluster2"}
        assert {n["node"] for n in top["nodes"]} == {"talker", "listener", "listener2"}
        (chatter,) = top["topics"]
        assert chatter["topic"] == "/chatter" and chatter["rate_hz"] == pytest.approx(10.0, abs=1.5)
        assert 15 < chatter["bytes_per_s"] / chatter["rate_hz"] < 40  # "hello world N" as CDR, per message
        listener = next(n for n in top["nodes"] if n["node"] == "listener")
        assert 0 < listener["callback_p50_ms"] <= listener["callback_p99_ms"]
        drawn = hetros(env, "graph", "--live", "--out", str(tmp_path / "live")).stdout
        assert 8.0 <= float(re.search(r"talker -> listener, listener2  \(([\d.]+) Hz\)", drawn)[1]) <= 12.0
        assert 'label="shm ' in (tmp_path / "live.dot").read_text()
        deadline = time.monotonic() + 10
        while "I heard: [from the command line]" not in log.read_text() and time.monotonic() < deadline:
            time.sleep(0.1)
    heard = [line for line in log.read_text().splitlines() if "I heard: [from the command line]" in line]
    assert len(heard) == 2, log.read_text()  # both listeners, once each


def test_a_service_is_called_and_bad_requests_are_refused(tmp_path: Path, env: dict[str, str]) -> None:
    shutil.copy(EXAMPLES / "add_two_ints" / "nodes.py", tmp_path)
    project = tmp_path / "project.yaml"
    data = yaml.safe_load((EXAMPLES / "add_two_ints" / "project.yaml").read_text())
    del data["nodes"]["client"]
    del data["targets"]["client_proc"]
    project.write_text(yaml.safe_dump(data))
    with running(project, env, tmp_path / "launch.log"):
        # as `ros2 service list -t`: the node's parameter services beside its own
        parameter_services = ["describe_parameters [rcl_interfaces/srv/DescribeParameters]",
                              "get_parameter_types [rcl_interfaces/srv/GetParameterTypes]",
                              "get_parameters [rcl_interfaces/srv/GetParameters]",
                              "list_parameters [rcl_interfaces/srv/ListParameters]",
                              "set_parameters [rcl_interfaces/srv/SetParameters]",
                              "set_parameters_atomically [rcl_interfaces/srv/SetParametersAtomically]"]
        assert hetros(env, "service", "list", "-t").stdout.splitlines() == [
            "/add_two_ints [example_interfaces/srv/AddTwoInts]", *(f"/server/{s}" for s in parameter_services)]
        got = hetros(env, "service", "call", "/server/get_parameter_types", "rcl_interfaces/srv/GetParameterTypes",
                     "{names: [nonexistent]}")
        assert "GetParameterTypes_Response(types=" in got.stdout
        called = hetros(env, "service", "call", "/add_two_ints", "example_interfaces/srv/AddTwoInts", "{a: 2, b: 40}")
        assert called.stdout == ("requester: making request: example_interfaces.srv.AddTwoInts_Request(a=2, b=40)\n\n"
                                 "response:\nexample_interfaces.srv.AddTwoInts_Response(sum=42)\n\n")
        wrong = hetros(env, "service", "call", "/add_two_ints", "example_interfaces/srv/AddTwoInts", "{a: 2, c: 1}",
                       check=False)
        assert wrong.returncode == 1 and "has no field 'c'; its fields are a, b" in wrong.stderr
        typo = hetros(env, "service", "call", "/add_two_int", "example_interfaces/srv/AddTwoInts", check=False)
        assert "has no service /add_two_int (did you mean /add_two_ints?)" in typo.stderr
        off_range = hetros(env, "service", "call", "/add_two_ints", "example_interfaces/srv/AddTwoInts",
                           "{a: 99999999999999999999}", check=False)
        assert off_range.returncode == 1 and "AddTwoInts_Request.a" in off_range.stderr
        assert "sum=3" in hetros(env, "service", "call", "/add_two_ints", "example_interfaces/srv/AddTwoInts",
                                 "{a: 1, b: 2}").stdout


def test_service_echo_shows_ros2_demos_introspection_as_its_parameters_set_it(tmp_path: Path,
                                                                              env: dict[str, str]) -> None:
    """ros2/demos' introspection demo, unchanged: its client and service start with introspection
    'disabled' (nothing to echo); `param set ... contents` on both gives every call's four events with
    request and response, `metadata` the events alone, as `ros2 service echo` prints them."""
    demos = Path(__file__).resolve().parents[1] / "data" / "ros2_demos" / "demo_nodes_py"
    made = hetros(env, "init", str(demos), "-o", str(tmp_path / "all.yaml"), "--name", "intro")
    project = yaml.safe_load((tmp_path / "all.yaml").read_text())
    project["nodes"] = {"introspection": project["nodes"]["introspection"]}
    project["targets"] = {project["nodes"]["introspection"]["target"]: {"kind": "process"}}
    project.pop("topics", None)
    (tmp_path / "project.yaml").write_text(yaml.safe_dump(project))
    assert made.returncode == 0
    with running(tmp_path / "project.yaml", env, tmp_path / "launch.log"):
        quiet = hetros(env, "service", "echo", "/add_two_ints", "--duration", "1.5")
        assert quiet.stdout == "", quiet.stdout
        # one main made both nodes: each is found by its own name, its parameters its own
        listed = hetros(env, "node", "list").stdout.split()
        assert {"/introspection_client", "/introspection_service"} <= set(listed), listed
        got = hetros(env, "param", "get", "/introspection_service", "service_configure_introspection").stdout
        assert got == "String value is: disabled\n", got
        assert hetros(env, "param", "get", "/introspection_service", "client_configure_introspection",
                      check=False).stdout == "Parameter not set\n"
        for node, side in (("/introspection_client", "client"), ("/introspection_service", "service")):
            hetros(env, "param", "set", node, f"{side}_configure_introspection", "contents")
        echoed = hetros(env, "service", "echo", "/add_two_ints", "example_interfaces/srv/AddTwoInts", "-n", "8",
                        "--duration", "20").stdout
        events = [yaml.safe_load(block) for block in echoed.split("---\n") if block.strip()]
        assert len(events) == 8, echoed
        kinds = [event["info"]["event_type"] for event in events]
        first = kinds.index("REQUEST_SENT")
        call = events[first:first + 4]
        assert kinds[first:first + 4] == ["REQUEST_SENT", "REQUEST_RECEIVED", "RESPONSE_SENT", "RESPONSE_RECEIVED"]
        assert len({event["info"]["sequence_number"] for event in call}) == 1
        assert len({tuple(event["info"]["client_gid"]) for event in call}) == 1
        assert [event["request"] for event in call[:2]] == [[{"a": 2, "b": 3}]] * 2
        assert [event["response"] for event in call[2:]] == [[{"sum": 5}]] * 2
        for node, side in (("/introspection_client", "client"), ("/introspection_service", "service")):
            hetros(env, "param", "set", node, f"{side}_configure_introspection", "metadata")
        bare = hetros(env, "service", "echo", "/add_two_ints", "--once", "--duration", "20", "--flow-style").stdout
        assert "request: []" in bare and "response: []" in bare and "event_type: " in bare, bare
        wrong = hetros(env, "service", "echo", "/add_two_ints", "std_srvs/srv/Empty", check=False)
        assert wrong.returncode != 0 and "is a example_interfaces/srv/AddTwoInts, not a" in wrong.stderr


def test_an_action_goal_is_sent_and_its_result_printed(tmp_path: Path, env: dict[str, str]) -> None:
    example = EXAMPLES / "sort_action"
    data = yaml.safe_load((example / "project.yaml").read_text())
    del data["nodes"]["client"]
    data["messages"] = [str(example / "msg")]
    project = tmp_path / "project.yaml"
    project.write_text(yaml.safe_dump(data))
    env = dict(env, PYTHONPATH=os.pathsep.join(filter(None, [str(example), env.get("PYTHONPATH", "")])))
    with running(project, env, tmp_path / "launch.log"):
        assert hetros(env, "action", "list", "-t").stdout == "/sort [sorter_msgs/action/Sort]\n"
        assert hetros(env, "action", "info", "/sort", "-t").stdout == (
            "Action: /sort\nAction clients: 0\nAction servers: 1\n    /sorter [sorter_msgs/action/Sort]\n")
        unknown = hetros(env, "action", "info", "/nope", check=False)
        assert unknown.returncode == 1 and "has no action /nope (its actions: /sort)" in unknown.stderr
        sent = hetros(env, "action", "send_goal", "/sort", "sorter_msgs/action/Sort", "{unsorted: [5, 3, 9, 1]}")
        assert "Sending goal:\n     unsorted:\n     - 5\n" in sent.stdout
        assert re.search(r"Goal accepted with ID: [0-9a-f]{32}\n\nResult:\n    sorted:\n    - 1\n    - 3\n    - 5\n"
                         r"    - 9\n", sent.stdout), sent.stdout
        assert sent.stdout.endswith("Goal finished with status: SUCCEEDED\n")
        wrong = hetros(env, "action", "send_goal", "/sort", "sorter_msgs/action/Sort", "{unsorted: [-1]}", check=False)
        assert wrong.returncode == 1 and "unsorted" in wrong.stderr


def test_two_launches_at_once_do_not_mix_and_another_user_is_refused(tmp_path: Path, env: dict[str, str]) -> None:
    first = EXAMPLES / "talker_listener" / "project.yaml"
    second = EXAMPLES / "talker_listener" / "project_threads.yaml"
    with running(first, env, tmp_path / "first.log"), running(second, env, tmp_path / "second.log"):
        ambiguous = hetros(env, "topic", "list", check=False)
        assert ambiguous.returncode == 1 and "2 launches of any project are running" in ambiguous.stderr
        sessions = {r["project"]: r["session"] for r in json.loads(hetros(env, "ps", "--json").stdout)}
        assert set(sessions) == {"talker_listener", "talker_listener_threads"}
        threads = json.loads(hetros(env, "top", "--json", "--once", "--session",
                                    sessions["talker_listener_threads"]).stdout)
        assert {p["process"] for p in threads["processes"]} == {"launcher"}
        by_project = json.loads(hetros(env, "top", "--json", "--once", "--project", str(first)).stdout)
        assert {p["process"] for p in by_project["processes"]} == {"cluster1", "cluster2"}
        echoed = hetros(env, "topic", "echo", "/chatter", "--once", "--session", sessions["talker_listener_threads"])
        assert echoed.stdout.startswith("data: hello world")  # an in-process (inproc) topic, tapped alike
        if os.geteuid() != 0:
            return
        folder = Path(env["XDG_RUNTIME_DIR"]) / "hetros" / "launches" / sessions["talker_listener"]
        os.chmod(tmp_path, 0o755)
        os.chmod(Path(env["XDG_RUNTIME_DIR"]), 0o755)
        system_python = "/usr/bin/python3"  # the venv's interpreter lives where nobody may not read
        if not Path(system_python).exists():
            return
        probe = ("import os, socket, sys\n"
                 "s = socket.socket(socket.AF_UNIX)\n"
                 "try:\n    d = os.open(os.path.dirname(sys.argv[1]), os.O_RDONLY)\n"
                 "    s.connect(f'/proc/self/fd/{d}/' + os.path.basename(sys.argv[1]))\n"
                 "except PermissionError:\n    print('refused')\n"
                 "else:\n    print('connected')\n"
                 "try:\n    open(sys.argv[2]).read()\nexcept PermissionError:\n    print('refused')\n"
                 "else:\n    print('read')\n")
        as_nobody = subprocess.run([system_python, "-c", probe, str(folder / "cluster1.sock"),
                                    str(folder / "plan.json")], capture_output=True, text=True, timeout=30,
                                   user="nobody", check=False)
        assert as_nobody.stdout.split() == ["refused", "refused"], as_nobody.stderr


SIM_NODES = '''
from hetros import Node
from hetros.interfaces.std_msgs.msg import String


def ticker(node: Node) -> None:
    node.create_timer(1.0, lambda: node.log.info("tick at %d", node.get_clock().now().nanoseconds))


def echo(node: Node) -> None:
    pub = node.create_publisher(String, "/echoed")

    def heard(message: String) -> None:
        node.log.info("heard %s at %d", message.data, node.get_clock().now().nanoseconds)
        pub.publish(String(data=f"{message.data}@{node.get_clock().now().nanoseconds}"))
    node.create_subscription(String, "/chatter", heard)
'''


def _sim_project(folder: Path, kind: str) -> Path:
    folder.mkdir()
    (folder / "nodes.py").write_text(SIM_NODES)
    project = folder / "project.yaml"
    project.write_text(yaml.safe_dump({
        "name": f"sim_{kind}", "use_sim_time": True,
        "targets": {"a": {"kind": kind}, "b": {"kind": kind}},
        "nodes": {"ticker": {"run": "nodes:ticker", "target": "a"},
                  "echo": {"run": "nodes:echo", "target": "b", "subscribe": {"/chatter": "std_msgs/msg/String"},
                           "publish": {"/echoed": "std_msgs/msg/String"}}}}))
    return project


def _recording(path: Path) -> None:
    from rosbags.rosbag2 import StoragePlugin, Writer

    from hetros.msg import registry
    from hetros.transport import MessageCodec

    types = registry()
    codec = MessageCodec(types, "std_msgs/msg/String")
    writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    connection = writer.add_connection("/chatter", "std_msgs/msg/String", typestore=types.store)
    for index in range(6):
        message = types.get("std_msgs/msg/String")(data=f"m{index}")
        writer.write(connection, 10_000_000_000 + index * 500_000_000, bytes(codec.encode(message)))
    writer.close()


def test_sim_time_and_lockstep_replay_give_the_same_outputs_in_every_mapping(tmp_path: Path,
                                                                             env: dict[str, str]) -> None:
    """use_sim_time: the clock is /clock's; `play --lockstep --launch` starts the consumers of a recording and
    delivers each message in its own time once they finished the one before: the same outputs on every replay
    and mapping."""
    bag = tmp_path / "bag"
    _recording(bag)
    heard_per_run = []
    for run, kind in enumerate(("process", "process", "thread")):
        project = _sim_project(tmp_path / f"run{run}", kind)
        played = hetros(env, "play", str(bag), "--lockstep", "--launch", str(project), timeout=120)
        assert "played 6 messages: /chatter 6" in played.stdout, played.stderr
        heard = re.findall(r"heard (m\d) at (\d+)", played.stderr)
        assert heard == [(f"m{i}", str(10_000_000_000 + i * 500_000_000)) for i in range(6)], played.stderr
        ticks = [int(t) for t in re.findall(r"tick at (\d+)", played.stderr)]
        assert ticks and all(t >= 10_000_000_000 for t in ticks), played.stderr  # the timer runs on /clock
        heard_per_run.append(heard)
    assert heard_per_run[0] == heard_per_run[1] == heard_per_run[2]


def test_a_recording_holds_what_was_published_and_plays_back_into_a_running_launch(tmp_path: Path,
                                                                                   env: dict[str, str]) -> None:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    recorded = tmp_path / "run.mcap"
    launched = subprocess.run([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "talker_listener" /
                               "project.yaml"), "--duration", "3", "--record", str(recorded)], capture_output=True,
                              text=True, env=env, timeout=120, check=False)
    assert launched.returncode == 0, launched.stderr
    store = get_typestore(Stores.ROS2_JAZZY)  # rosbags' own decoder: what ROS 2 tools read
    with Reader(recorded) as reader:
        (connection,) = reader.connections
        assert (connection.topic, connection.msgtype) == ("/chatter", "std_msgs/msg/String")
        (qos,) = connection.ext.offered_qos_profiles  # what the project offers: ros2 bag play offers it again
        assert (qos.history.name, qos.depth, qos.reliability.name, qos.durability.name) == \
            ("KEEP_ALL", 10, "RELIABLE", "VOLATILE")
        texts = [store.deserialize_cdr(data, connection.msgtype).data for _, _, data in reader.messages()]
    assert texts[:3] == ["hello world 0", "hello world 1", "hello world 2"]  # from the very first message
    assert len(texts) >= 25
    assert b"relative_file_paths:\n- run.mcap\n" in recorded.read_bytes()  # the metadata names the file itself
    info = hetros(env, "bag", "info", str(recorded)).stdout
    assert info.startswith("Files:             run.mcap\nBag size:          ") and "Storage id:        mcap\n" in info
    assert re.search(r"^Duration:          [23]\.\d{9}s$", info, re.MULTILINE), info
    assert f"Messages:          {len(texts)}\n" in info
    assert info.endswith(f"Topic information: Topic: /chatter | Type: std_msgs/msg/String | Count: {len(texts)} | "
                         "Serialization Format: cdr\n")
    log = tmp_path / "listeners.log"
    with running(EXAMPLES / "talker_listener" / "project.yaml", env, log):
        assert hetros(env, "play", str(recorded), "--rate", "4").stdout == f"played {len(texts)} messages: " \
            f"/chatter {len(texts)}\n"
        deadline = time.monotonic() + 10
        while log.read_text().count("I heard: [hello world 2]") < 4 and time.monotonic() < deadline:
            time.sleep(0.1)
    assert log.read_text().count("I heard: [hello world 2]") >= 4  # each listener: the talker's and the replay's


def test_the_vehicles_image_topic_is_echoed_without_slowing_its_publisher(tmp_path: Path,
                                                                          env: dict[str, str]) -> None:
    """examples/lane_following: 640x480 rgb8 images on loans over shared memory; echoing them does not slow
    the camera, and the header stamps (node.get_clock()) give the chain's delay."""
    with running(EXAMPLES / "lane_following" / "project.yaml", env, tmp_path / "launch.log"):
        described = hetros(env, "topic", "echo", "/image_raw", "--once", "--no-arr").stdout
        assert "data: '<sequence type: uint8, length: 921600>'" in described and "encoding: rgb8" in described
        shown = yaml.safe_load(hetros(env, "topic", "echo", "/image_raw", "--once").stdout.split("---")[0])
        assert len(shown["data"]) == 129 and shown["data"][-1] == "..." and any(shown["data"][:128])
        with subprocess.Popen([sys.executable, "-m", "hetros", "topic", "echo", "/image_raw", "--duration", "4.5"],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) as echo:
            rate = _last_figures(hetros(env, "topic", "hz", "/image_raw", "--duration", "3.2").stdout,
                                 r"average rate: ([\d.]+)")[0]
            echoed, _ = echo.communicate(timeout=60)
        assert rate == pytest.approx(10.0, rel=0.05)  # the camera's rate while every image is echoed
        assert echoed.count("---\n") >= 25
        bandwidth = hetros(env, "topic", "bw", "/image_raw", "--duration", "3.2").stdout
        megabytes, size = _last_figures(bandwidth, r"([\d.]+) MB/s from \d+ messages\n\tMessage size mean: "
                                                   r"([\d.]+) KB")
        assert size == pytest.approx(921.65, abs=0.01) and megabytes == pytest.approx(size * 10 / 1000, rel=0.10)
        delay = _last_figures(hetros(env, "topic", "delay", "/cmd_vel", "--duration", "2.2").stdout,
                              r"average delay: ([\d.]+)")[0]
        assert 0 < delay < 2.0


@pytest.mark.rtl
@pytest.mark.skipif(shutil.which("verilator") is None, reason="Debian's verilator is not installed")
def test_a_hardware_topic_is_echoed_through_its_gateway(tmp_path: Path, env: dict[str, str]) -> None:
    """examples/sobel_hw on its fpga target: /image_edges comes out of the co-simulated Sobel, and its
    gateway's publisher is where the command line looks."""
    pytest.importorskip("amaranth")
    example = EXAMPLES / "sobel_hw"
    data = yaml.safe_load((example / "project_fpga.yaml").read_text())
    for node in ("camera", "display"):
        data["nodes"][node]["parameters"]["frames"] = 100_000
    data["nodes"]["camera"]["parameters"]["hz"] = 20.0
    project = tmp_path / "project_fpga.yaml"
    project.write_text(yaml.safe_dump(data))
    env = dict(env, PYTHONPATH=os.pathsep.join(filter(None, [str(example), env.get("PYTHONPATH", "")])))
    with running(project, env, tmp_path / "launch.log"):
        info = hetros(env, "topic", "info", "/image_edges", "-v").stdout
        assert "Node name: sobel" in info and "Target: fpga (hardware)" in info
        edges = yaml.safe_load(hetros(env, "topic", "echo", "/image_edges", "--once", "--full-length").stdout
                               .split("---")[0])
        assert (edges["width"], edges["height"], edges["encoding"]) == (64, 48, "mono8")
        assert len(edges["data"]) == 64 * 48 and max(edges["data"]) > 0
        top = json.loads(hetros(env, "top", "--json", "--once", "--interval", "1.5").stdout)
        assert {p["process"] for p in top["processes"]} == {"io", "fpga"}
        assert any(t["topic"] == "/image_edges" and t["rate_hz"] > 0 for t in top["topics"])
        ports = {g["port"]: g for g in top["gateways"]}
        assert ports and all(g["gateway"] == "hetros_gateway_fpga" for g in ports.values())
        assert any(g["messages"] > 0 and g["cycles_per_message"] > 64 * 48 / 8 for g in ports.values()), ports


def test_foxglove_sees_the_topics_with_their_schemas_and_messages(tmp_path: Path, env: dict[str, str]) -> None:
    """`hetros foxglove`: Foxglove's WebSocket protocol, as a Foxglove client speaks it."""
    pytest.importorskip("foxglove")
    sync_client = pytest.importorskip("websockets.sync.client")
    from hetros.msg import registry
    from hetros.transport import MessageCodec

    with running(EXAMPLES / "talker_listener" / "project.yaml", env, tmp_path / "launch.log"), \
            subprocess.Popen([sys.executable, "-m", "hetros", "foxglove", "--port", "0"], env=env, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE) as server:
        try:
            assert server.stdout is not None
            url = re.search(r"ws://[\d.]+:\d+", server.stdout.readline())
            assert url, server.stderr.read() if server.stderr else ""
            assert url[0].startswith("ws://127.0.0.1:")
            with sync_client.connect(url[0], subprotocols=["foxglove.sdk.v1"], open_timeout=20) as socket_:
                channels: dict[str, dict[str, object]] = {}
                capabilities: list[str] = []
                while "/chatter" not in channels:
                    text = socket_.recv(timeout=20)
                    answer = json.loads(text) if isinstance(text, str) else {}
                    if answer.get("op") == "advertise":
                        channels.update({c["topic"]: c for c in answer["channels"]})
                    elif answer.get("op") == "serverInfo":
                        capabilities = answer["capabilities"]
                assert {"clientPublish", "parameters", "services"} <= set(capabilities), capabilities
                chatter = channels["/chatter"]
                assert (chatter["encoding"], chatter["schemaName"], chatter["schemaEncoding"]) == (
                    "cdr", "std_msgs/msg/String", "ros2msg")
                assert chatter["schema"] == "string data\n"
                socket_.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 7,
                                                                                "channelId": chatter["id"]}]}))
                while True:
                    frame = socket_.recv(timeout=20)
                    if isinstance(frame, bytes) and frame[0] == 1:
                        break
                assert int.from_bytes(frame[1:5], "little") == 7
                message = MessageCodec(registry(), "std_msgs/msg/String").decode(memoryview(frame[13:]))
                assert re.fullmatch(r"hello world \d+", message.data)
        finally:
            server.terminate()
            server.wait(30)


def test_a_foxglove_websocket_v1_client_subscribes_and_publishes(tmp_path: Path, env: dict[str, str]) -> None:
    """The older subprotocol (Foxglove Studio, Lichtblick) on the same port: the channels, a subscription's
    messageData frames, and a client-advertised channel whose message reaches the launch's listeners."""
    pytest.importorskip("foxglove")
    sync_client = pytest.importorskip("websockets.sync.client")
    from hetros.msg import registry
    from hetros.transport import MessageCodec

    codec = MessageCodec(registry(), "std_msgs/msg/String")
    log = tmp_path / "launch.log"
    with running(EXAMPLES / "talker_listener" / "project.yaml", env, log), \
            subprocess.Popen([sys.executable, "-m", "hetros", "foxglove", "--port", "0"], env=env, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE) as server:
        try:
            assert server.stdout is not None
            url = re.search(r"ws://[\d.]+:\d+", server.stdout.readline())
            assert url, server.stderr.read() if server.stderr else ""
            with sync_client.connect(url[0], subprotocols=["foxglove.websocket.v1"], open_timeout=20) as socket_:
                assert socket_.subprotocol == "foxglove.websocket.v1"
                info = json.loads(socket_.recv(timeout=20))
                assert info["op"] == "serverInfo" and "clientPublish" in info["capabilities"]
                advertised = json.loads(socket_.recv(timeout=20))
                chatter = next(c for c in advertised["channels"] if c["topic"] == "/chatter")
                assert (chatter["encoding"], chatter["schemaName"], chatter["schema"]) == (
                    "cdr", "std_msgs/msg/String", "string data\n")
                socket_.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 3, "channelId": chatter["id"]}]}))
                while not isinstance(frame := socket_.recv(timeout=20), bytes):
                    pass
                assert frame[0] == 1 and int.from_bytes(frame[1:5], "little") == 3
                assert re.fullmatch(r"hello world \d+", codec.decode(memoryview(frame[13:])).data)
                socket_.send(json.dumps({"op": "clientAdvertise", "channels": [
                    {"id": 9, "topic": "/chatter", "encoding": "cdr", "schemaName": "std_msgs/msg/String"},
                    {"id": 10, "topic": "/nowhere", "encoding": "cdr", "schemaName": "std_msgs/msg/String"}]}))
                String = registry().get("std_msgs/msg/String")
                socket_.send(b"\x01" + (9).to_bytes(4, "little") + bytes(codec.encode(String(data="from foxglove"))))
                deadline = time.monotonic() + 20
                while "I heard: [from foxglove]" not in log.read_text() and time.monotonic() < deadline:
                    time.sleep(0.1)
                assert log.read_text().count("I heard: [from foxglove]") == 2  # both listeners
                statuses = []
                while len(statuses) < 1:
                    reply = socket_.recv(timeout=20)
                    if isinstance(reply, str) and json.loads(reply)["op"] == "status":
                        statuses.append(json.loads(reply)["message"])
                assert statuses[0].startswith("client channel /nowhere: the launch has no such topic")
        finally:
            server.terminate()
            server.wait(30)


BUSY_NODES = """
import textwrap
import time

from hetros import Node
from hetros.interfaces.std_msgs.msg import String


def fast(node: Node) -> None:
    publisher = node.create_publisher(String, node.get_parameter("topic"))
    for tick in node.rate(200.0):
        publisher.publish(String(data=str(tick)))


def slow(node: Node) -> None:
    node.create_subscription(String, node.get_parameter("topic"), lambda message: time.sleep(0.02))
"""


@pytest.mark.parametrize("kind", ["process", "thread"])
def test_top_counts_a_slow_subscribers_stalls_and_drops(tmp_path: Path, env: dict[str, str], kind: str) -> None:
    """A reliable keep_all topic holds its publisher back (stalls); a keep_last one drops the oldest."""
    (tmp_path / "nodes.py").write_text(BUSY_NODES)
    project = tmp_path / "project.yaml"
    project.write_text(yaml.safe_dump({
        "name": f"busy_{kind}", "targets": {"a": {"kind": kind}, "b": {"kind": kind}},
        "nodes": {f"{role}_{topic}": {"run": f"nodes:{role}", "target": target, "parameters": {"topic": f"/{topic}"},
                                      section: {f"/{topic}": "std_msgs/msg/String"}}
                  for topic in ("steady", "lossy")
                  for role, target, section in (("fast", "a", "publish"), ("slow", "b", "subscribe"))},
        "topics": {"/steady": {"depth": 2}, "/lossy": {"history": "keep_last", "depth": 1}}}))
    with running(project, env, tmp_path / "launch.log"):
        time.sleep(1.0)
        rows = json.loads(hetros(env, "top", "--json", "--once").stdout)
    topics = {t["topic"]: t for t in rows["topics"]}
    assert topics["/steady"]["stalls"] > 0 and topics["/steady"]["dropped"] == 0, topics
    assert topics["/lossy"]["dropped"] > 0 and topics["/lossy"]["stalls"] == 0, topics
    # held to the subscriber's pace (50 Hz), or not (the publisher's 200 Hz): a ratio, since a loaded machine
    # stretches both and the first interval holds the start's burst
    assert topics["/steady"]["rate_hz"] < 0.75 * topics["/lossy"]["rate_hz"], topics


CAMERA_NODES = """
import numpy as np

from hetros import Node
from hetros.interfaces.sensor_msgs.msg import Image


def camera(node: Node) -> None:
    pub = node.create_publisher(Image, "/image")
    pixels = np.zeros(640 * 480 * 3, dtype=np.uint8)
    for i in node.rate(20.0):
        pixels[:8] = i % 256
        pub.publish(Image(height=480, width=640, encoding="rgb8", step=640 * 3, data=pixels))


def sink(node: Node) -> None:
    node.create_subscription(Image, "/image", lambda message: None)
"""

CAMERA_PROJECT = """
name: camera
targets: {a: {kind: process}, b: {kind: process}}
nodes:
  camera: {run: nodes:camera, target: a, publish: {/image: sensor_msgs/msg/Image}}
  sink: {run: nodes:sink, target: b, subscribe: {/image: sensor_msgs/msg/Image}}
topics:
  /image: {reliability: best_effort, history: keep_last, depth: 2}
"""


def _rss_mb(pid: int) -> float:
    status = Path(f"/proc/{pid}/status").read_text()
    return int(re.search(r"VmRSS:\s+(\d+) kB", status)[1]) / 1024  # type: ignore[index]


def test_foxglove_clients_that_never_read_stay_bounded_and_slow_nobody(tmp_path: Path, env: dict[str, str]) -> None:
    """Five Foxglove clients subscribe to 1 MB images at 20 Hz and never read: the server's memory grows by
    at most 64 MB and the camera keeps its rate within 10 % (60 s with HETROS_SOAK=1, else 8 s)."""
    pytest.importorskip("foxglove")
    sync_client = pytest.importorskip("websockets.sync.client")
    (tmp_path / "nodes.py").write_text(CAMERA_NODES)
    project = tmp_path / "camera.yaml"
    project.write_text(CAMERA_PROJECT)
    soak = 60.0 if os.environ.get("HETROS_SOAK") else 8.0
    with running(project, env, tmp_path / "launch.log", duration=soak + 60), \
            subprocess.Popen([sys.executable, "-m", "hetros", "foxglove", "--port", "0"], env=env, text=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE) as server:
        try:
            assert server.stdout is not None
            url = re.search(r"ws://[\d.]+:\d+", server.stdout.readline())
            assert url, server.stderr.read() if server.stderr else ""
            clients = []
            for _ in range(5):
                client = sync_client.connect(url[0], subprotocols=["foxglove.sdk.v1"], open_timeout=20,
                                             close_timeout=1, max_size=None)
                channel = None
                while channel is None:
                    answer = json.loads(text) if isinstance(text := client.recv(timeout=20), str) else {}
                    if answer.get("op") == "advertise":
                        channel = next((c for c in answer["channels"] if c["topic"] == "/image"), None)
                client.send(json.dumps({"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channel["id"]}]}))
                clients.append(client)  # and never read again
            time.sleep(3.0)
            before = _rss_mb(server.pid)
            rate = _last_figures(hetros(env, "topic", "hz", "/image", "--duration", str(soak / 2)).stdout,
                                 r"average rate: ([\d.]+)")[0]
            time.sleep(soak / 2)
            after = _rss_mb(server.pid)
            assert server.poll() is None
            assert after - before <= 64, f"the server grew from {before:.0f} MB to {after:.0f} MB"
            assert rate == pytest.approx(20.0, rel=0.10)
            for client in clients:
                client.close()
        finally:
            server.terminate()
            server.wait(30)


def test_foxglove_refuses_an_interface_the_project_does_not_allow(tmp_path: Path, env: dict[str, str]) -> None:
    pytest.importorskip("foxglove")
    with running(EXAMPLES / "talker_listener" / "project.yaml", env, tmp_path / "launch.log"):
        done = hetros(env, "foxglove", "--host", "0.0.0.0", "--port", "0", check=False, timeout=30)
    assert done.returncode == 1
    assert "listens on 127.0.0.1 only, unless the project file lists the interface (foxglove_hosts" in done.stderr


def test_namespaced_nodes_go_by_their_full_ros_names(tmp_path: Path, env: dict[str, str]) -> None:
    """In a launch that puts the talker under /r2, the commands show /r2/talker and accept it, as ros2's do
    (the project's key for it, talker, is accepted too)."""
    shutil.copy(EXAMPLES / "talker_listener" / "nodes.py", tmp_path / "nodes.py")
    project = tmp_path / "project.yaml"
    project.write_text(textwrap.dedent("""\
        name: namespaced
        targets: {a: {kind: process}, b: {kind: process}}
        nodes:
          talker:   {run: nodes:talker, target: a, namespace: /r2, publish: {/chatter: std_msgs/msg/String},
                     parameters: {hz: 10.0}}
          listener: {run: nodes:listener, target: b, subscribe: {/chatter: std_msgs/msg/String}}
        """))
    with running(project, env, tmp_path / "launch.log"):
        assert hetros(env, "node", "list").stdout.split() == ["/listener", "/r2/talker"]
        assert hetros(env, "node", "info", "/r2/talker").stdout.startswith("/r2/talker\n")
        assert hetros(env, "param", "get", "/r2/talker", "hz").stdout.strip() == "Double value is: 10.0"
        assert hetros(env, "param", "get", "talker", "hz").stdout.strip() == "Double value is: 10.0"
        verbose = hetros(env, "topic", "info", "-v", "/chatter").stdout
        assert "Node name: talker\nNode namespace: /r2\n" in verbose
        missing = hetros(env, "node", "info", "/talker", check=False)
        assert missing.returncode != 0 and "no node /talker (its nodes: /listener, /r2/talker)" in missing.stderr


ROSBAG2 = Path(__file__).resolve().parents[1] / "data" / "rosbag2"


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_rosbag2s_own_talker_bag_plays_every_message_in_order(storage: str, tmp_path: Path,
                                                              env: dict[str, str]) -> None:
    """rosbag2_py's talker bag (zstd-chunked MCAP, and sqlite3): `bag info` gives its metadata's counts, and
    `play` delivers its ten /topic strings, in order, to a listener of a running graph."""
    bag = ROSBAG2 / storage / "talker"
    info = hetros(env, "bag", "info", str(bag)).stdout
    assert f"Storage id:        {storage}\n" in info and "Messages:          20\n" in info, info
    assert "Topic: /topic | Type: std_msgs/msg/String | Count: 10 |" in info, info
    (tmp_path / "nodes.py").write_text(textwrap.dedent("""\
        from hetros.interfaces.std_msgs.msg import String


        def listener(node):
            node.create_subscription(String, '/topic', lambda m: node.log.info(f'heard {m.data}'))
        """))
    project = tmp_path / "project.yaml"
    project.write_text(yaml.safe_dump({"name": "bagplay", "nodes": {"listener": {
        "run": "nodes:listener", "subscribe": {"/topic": "std_msgs/msg/String"}}}}))
    log = tmp_path / "listener.log"
    with running(project, env, log):
        played = hetros(env, "play", str(bag), "--rate", "8", "--topics", "/topic")
        assert played.stdout == "played 10 messages: /topic 10\n", played.stderr
        deadline = time.monotonic() + 10
        while log.read_text().count("heard Hello") < 10 and time.monotonic() < deadline:
            time.sleep(0.1)
    heard = re.findall(r"heard (Hello, world! \d+)", log.read_text())
    assert heard == [f"Hello, world! {i}" for i in range(10)], log.read_text()
    if storage != "mcap":
        return
    # ros2 bag play's --start-offset (from the bag's start) and --remap onto the launch's own topic
    (tmp_path / "other.yaml").write_text(yaml.safe_dump({"name": "bagplay2", "nodes": {"listener": {
        "run": "nodes:listener", "remap": {"/topic": "/chatter"}, "subscribe": {"/chatter": "std_msgs/msg/String"}}}}))
    log2 = tmp_path / "listener2.log"
    with running(tmp_path / "other.yaml", env, log2):
        played = hetros(env, "play", str(bag), "--rate", "8", "--topics", "/topic", "--start-offset", "2.2",
                        "--remap", "/topic:=/chatter")
        assert played.stdout == "played 5 messages: /chatter 5\n", played.stderr
        # a running graph's QoS is planned: an override that contradicts it is refused, naming the file
        overrides = tmp_path / "overrides.yaml"
        overrides.write_text("/chatter: {reliability: best_effort, history: keep_last, depth: 5}\n")
        refused = hetros(env, "play", str(bag), "--topics", "/topic", "--remap", "/topic:=/chatter",
                         "--qos-profile-overrides-path", str(overrides), check=False)
        assert refused.returncode != 0, refused.stdout
        assert f"{overrides}: /chatter.reliability is best_effort, but launch" in refused.stderr, refused.stderr
        assert "hetros play --launch" in refused.stderr
        deadline = time.monotonic() + 10
        while log2.read_text().count("heard Hello") < 5 and time.monotonic() < deadline:
            time.sleep(0.1)
    assert re.findall(r"heard (Hello, world! \d+)", log2.read_text()) == [f"Hello, world! {i}" for i in range(5, 10)]
    # with --launch the override is the QoS the topic is launched with: a subscription that asks for
    # reliable delivery cannot be served by a best-effort player, reported as ROS 2 reports it
    (tmp_path / "asks.yaml").write_text(yaml.safe_dump({"name": "bagplay3", "nodes": {"listener": {
        "run": "nodes:listener", "subscribe": {"/topic": {"type": "std_msgs/msg/String",
                                                          "reliability": "reliable"}}}}}))
    (tmp_path / "best_effort.yaml").write_text("/topic:\n  reliability: best_effort\n  history: keep_last\n"
                                               "  depth: 10\n  deadline: {sec: 2147483647, nsec: 4294967295}\n")
    asks = hetros(env, "play", str(bag), "--launch", str(tmp_path / "asks.yaml"), "--rate", "8",
                  "--qos-profile-overrides-path", str(tmp_path / "best_effort.yaml"), check=False)
    assert asks.returncode != 0 and "RELIABILITY" in asks.stderr.upper(), asks.stderr
    (tmp_path / "reliable.yaml").write_text("/topic: {reliability: reliable, durability: volatile}\n")
    served = hetros(env, "play", str(bag), "--launch", str(tmp_path / "asks.yaml"), "--rate", "8",
                    "--qos-profile-overrides-path", str(tmp_path / "reliable.yaml"), check=False)
    assert served.returncode == 0, served.stderr
    assert re.findall(r"heard (Hello, world! \d+)", served.stderr) == [f"Hello, world! {i}" for i in range(10)]


@pytest.mark.parametrize("mode", ["none", "file", "message"])
def test_a_recording_reads_back_with_rosbags_and_the_mcap_library(mode: str, tmp_path: Path,
                                                                  env: dict[str, str]) -> None:
    import io

    import zstandard
    from mcap.reader import make_reader
    from rosbags.rosbag2 import Reader

    recorded = tmp_path / "run"
    with running(EXAMPLES / "talker_listener" / "project.yaml", env, tmp_path / "launch.log"):
        done = hetros(env, "record", "-t", "/chatter", "-o", str(recorded), "--duration", "2",
                      "--compression-mode", mode)
    written = int(re.search(r"wrote .*: (\d+) messages", done.stdout).group(1))  # type: ignore[union-attr]
    assert written >= 5, done.stdout + done.stderr
    with Reader(recorded) as reader:
        assert reader.compression_mode == ("" if mode == "none" else mode)
        assert sum(1 for _ in reader.messages()) == written == reader.message_count
    files = sorted(recorded.glob("*.mcap*")) if recorded.is_dir() else [recorded]
    assert len(files) == 1, files
    raw = files[0].read_bytes()
    if mode == "file":
        assert files[0].name.endswith(".mcap.zstd")
        raw = zstandard.ZstdDecompressor().decompressobj().decompress(raw)
    seen = [(channel.topic, schema.name if schema else "")
            for schema, channel, _message in make_reader(io.BytesIO(raw)).iter_messages()]
    assert seen == [("/chatter", "std_msgs/msg/String")] * written
    info = hetros(env, "bag", "info", str(recorded)).stdout
    assert f"Messages:          {written}\n" in info, info
