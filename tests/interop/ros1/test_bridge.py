"""A project's topics exported to and imported from stock ROS 1 (rospy) through `external: ros1:`."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from hetros import CheckError
from hetros.project import load_project, plan
from tests.support.ros1 import LISTENER, ROS_PYTHON, compile_roscpp, needs_ros1, needs_roscpp, run_ros, stop

NODES = textwrap.dedent('''
    import time
    from hetros.interfaces.std_msgs.msg import String

    def talker(node):
        pub = node.create_publisher(String, "/chatter")
        i = 0
        while not node.graph.stop.is_set():
            pub.publish(String(data=f"hello {i}"))
            i += 1
            time.sleep(0.05)

    def listener(node):
        with open(node.get_parameter("out"), "a") as out:
            for message in node.create_subscription(String, "/from_ros1"):
                out.write(message.data + "\\n")
                out.flush()
''')

ROS1_TALKER = textwrap.dedent("""
    import rospy
    from std_msgs.msg import String
    rospy.init_node("ros1_talker")
    pub = rospy.Publisher("/from_ros1", String, queue_size=10)
    rate = rospy.Rate(20)
    while not rospy.is_shutdown():
        pub.publish(String(data="from ROS 1"))
        rate.sleep()
""")


def _project(tmp_path: Path, external: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: bridge_demo
        targets: {{main: {{kind: thread}}, worker: {{kind: process}}}}
        nodes:
          talker: {{run: nodes:talker, target: worker, publish: {{/chatter: std_msgs/msg/String}}}}
          listener: {{run: nodes:listener, target: main, parameters: {{out: {tmp_path / "got.txt"}}},
                     subscribe: {{/from_ros1: std_msgs/msg/String}}}}
        external:
        {textwrap.indent(external.strip(), "  ")}
    """))
    return tmp_path / "project.yaml"


@needs_ros1
def test_exported_and_imported_topics_reach_stock_rospy(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    uri, env = ros_master
    project = _project(tmp_path, f"ros1: {{master: '{uri}', export: [/chatter], import: [/from_ros1]}}")
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "25"],
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    (tmp_path / "talker.py").write_text(ROS1_TALKER)
    (tmp_path / "listener.py").write_text(LISTENER)
    ros1_talker = subprocess.Popen([ROS_PYTHON, str(tmp_path / "talker.py")], env=env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        listened = subprocess.run([ROS_PYTHON, str(tmp_path / "listener.py")], env=env, capture_output=True,
                                  text=True, timeout=60, check=False)
        assert listened.stdout.startswith("got 5 hello "), listened.stdout + listened.stderr
        deadline = time.monotonic() + 20
        got = tmp_path / "got.txt"
        while not (got.exists() and "from ROS 1" in got.read_text()) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert got.exists() and "from ROS 1" in got.read_text()
    finally:
        stop(ros1_talker)
        out = stop(launch, 30)
    assert "ROS 1 bridge /bridge_demo_hetros" in out, out


@pytest.mark.parametrize(("external", "expected"), [
    ("ros1: {export: [/nothing]}", r"external\.ros1\.export\.0.*/nothing has no hetros publisher to export"),
    ("ros1: {import: [/chatter]}", r"external\.ros1\.import\.0.*/chatter has no hetros subscriber to import"),
    ("ros1: {master: 'localhost:11311'}", r"master must be a URI like 'http://127.0.0.1:11311/'"),
    ("ros1: {export_services: [/none]}", r"external\.ros1\.export_services\.0.*/none has no hetros server to export"),
    ("ros1: {import_services: [/none]}", r"external\.ros1\.import_services\.0.*/none has no hetros client to "
                                         r"import"),
])
def test_bad_ros1_sections_are_refused_by_check(tmp_path: Path, external: str, expected: str) -> None:
    project = _project(tmp_path, external)
    with pytest.raises(Exception, match=expected):
        plan(load_project(project))


def test_a_type_ros1_does_not_know_is_refused_by_check(tmp_path: Path) -> None:
    project = _project(tmp_path, "ros1: {export: [/chatter]}")
    text = project.read_text().replace("/chatter: std_msgs/msg/String", "/chatter: example_interfaces/msg/String")
    project.write_text(text)
    with pytest.raises(CheckError, match=r"external\.ros1\.export\.0.*example_interfaces/msg/String has no ROS 1 "
                                         r"definition"):
        plan(load_project(project))


@needs_ros1
def test_ros1_parameters_reach_node_get_parameter(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    uri, env = ros_master
    from tests.support.ros1 import run_ros

    run_ros(env, "rosparam", "set", "/robot/speed", "2.5")
    run_ros(env, "rosparam", "set", "/reader/gain", "7")
    (tmp_path / "params.py").write_text(textwrap.dedent('''
        import json

        def reader(node):
            values = [node.get_parameter("/robot/speed"), node.get_parameter("~gain"),
                      node.get_parameter("local"), node.get_parameter("missing", "fallback")]
            with open(node.get_parameter("out"), "w") as out:
                json.dump(values, out)
    '''))
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: params_demo
        nodes:
          reader: {{run: params:reader, target: main, parameters: {{local: 1, out: {tmp_path / "values.json"}}}}}
        external:
          ros1: {{master: '{uri}'}}
    """))
    done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "5"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=60, check=False)
    assert (tmp_path / "values.json").read_text() == "[2.5, 7, 1, \"fallback\"]", done.stdout + done.stderr


@needs_ros1
def test_a_transient_local_topic_is_latched_for_late_ros1_subscribers(ros_master: tuple[str, dict[str, str]],
                                                                       tmp_path: Path) -> None:
    uri, env = ros_master
    from tests.support.ros1 import run_ros

    (tmp_path / "mapper.py").write_text(textwrap.dedent('''
        from hetros.interfaces.std_msgs.msg import String

        def mapper(node):
            node.create_publisher(String, "/map").publish(String(data="the map"))
            node.spin()
    '''))
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: latch_demo
        nodes:
          mapper: {{run: mapper:mapper, target: main, publish: {{/map: std_msgs/msg/String}}}}
        topics:
          /map: {{durability: transient_local, depth: 1}}
        external:
          ros1: {{master: '{uri}', export: [/map]}}
    """))
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                               "--duration", "30"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True)
    try:
        time.sleep(4)  # published long before the ROS 1 subscriber exists
        assert 'data: "the map"' in run_ros(env, "rostopic", "echo", "-n", "1", "/map", timeout=60)
    finally:
        stop(launch, 30)


SERVICE_NODES = textwrap.dedent('''
    import time
    from hetros.interfaces.std_srvs.srv import SetBool

    def toggle(node):
        node.create_service(SetBool, "/hetros_toggle",
                            lambda request: SetBool.Response(success=request.data, message="hetros answers"))
        node.spin()

    def caller(node):
        client = node.create_client(SetBool, "/ros1_toggle")
        response = client.call(SetBool.Request(data=True), timeout=20.0)
        with open(node.get_parameter("out"), "w") as out:
            out.write(f"{response.success} {response.message}")
        node.spin()
''')


@needs_ros1
def test_services_are_exported_to_and_imported_from_ros1(ros_master: tuple[str, dict[str, str]],
                                                          tmp_path: Path) -> None:
    uri, env = ros_master
    from tests.interop.ros1.test_tcpros import ROS1_SERVER
    from tests.support.ros1 import run_ros

    (tmp_path / "services.py").write_text(SERVICE_NODES)
    (tmp_path / "server.py").write_text(ROS1_SERVER)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: services_demo
        targets: {{main: {{kind: thread}}, worker: {{kind: process}}}}
        nodes:
          toggle: {{run: services:toggle, target: worker, services: {{/hetros_toggle: std_srvs/srv/SetBool}}}}
          caller: {{run: services:caller, target: main, parameters: {{out: {tmp_path / "answer.txt"}}},
                   clients: {{/ros1_toggle: std_srvs/srv/SetBool}}}}
        external:
          ros1: {{master: '{uri}', export_services: [/hetros_toggle], import_services: [/ros1_toggle]}}
    """))
    server = subprocess.Popen([ROS_PYTHON, str(tmp_path / "server.py")], env=env, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
    run_ros(env, ROS_PYTHON, "-c", "import rospy; rospy.wait_for_service('/ros1_toggle', 20)")
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                               "--duration", "30"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True)
    try:
        run_ros(env, ROS_PYTHON, "-c", "import rospy; rospy.wait_for_service('/hetros_toggle', 20)")
        called = run_ros(env, "rosservice", "call", "/hetros_toggle", "data: true")
        assert "success: True" in called and "hetros answers" in called
        answer = tmp_path / "answer.txt"
        deadline = time.monotonic() + 20
        while not answer.exists() and time.monotonic() < deadline:
            time.sleep(0.1)
        assert answer.read_text() == "True ros1 True"
    finally:
        out = stop(launch, 30)
        stop(server)
    assert "exports /hetros_toggle, imports /ros1_toggle" in out, out


EXAMPLES = Path(__file__).resolve().parents[3] / "examples"


@needs_ros1
def test_the_talker_listener_example_joins_ros1_both_ways(master: tuple[str, dict[str, str]]) -> None:
    from tests.support.ros1 import run_ros

    _uri, env = master
    example = EXAMPLES / "talker_listener"
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", "project_ros1.yaml", "--duration", "30"],
                              cwd=example, env=dict(env, PYTHONPATH=""), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
    try:
        assert 'data: "hello world' in run_ros(env, "rostopic", "echo", "-n", "2", "/chatter", timeout=60)
        run_ros(env, "rostopic", "pub", "-1", "/chatter", "std_msgs/String", "data: from stock ROS 1", timeout=60)
        time.sleep(1)
        # every node's log lines, as rosgraph_msgs/Log on /rosout (what rqt_console reads)
        logged = run_ros(env, "rostopic", "echo", "-n", "3", "/rosout", timeout=60)
    finally:
        out = stop(launch, 30)
    assert "I heard: [from stock ROS 1]" in out, out
    assert 'msg: "I heard: [hello world' in logged and 'name: "/listener' in logged and "level: 2" in logged, logged


@needs_ros1
def test_the_set_bool_example_answers_rosservice(master: tuple[str, dict[str, str]]) -> None:
    from tests.support.ros1 import run_ros

    _uri, env = master
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", "project_ros1.yaml", "--duration", "30"],
                              cwd=EXAMPLES / "set_bool", env=dict(env, PYTHONPATH=""), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
    try:
        run_ros(env, ROS_PYTHON, "-c", "import rospy; rospy.wait_for_service('/set_bool', 30)", timeout=60)
        answered = run_ros(env, "rosservice", "call", "/set_bool", "true")
        assert "success: True" in answered and "set to True" in answered
    finally:
        stop(launch, 30)


@needs_ros1
@needs_roscpp
def test_the_set_bool_example_answers_a_compiled_roscpp_client(master: tuple[str, dict[str, str]],
                                                               tmp_path: Path) -> None:
    _uri, env = master
    client = compile_roscpp(EXAMPLES / "set_bool" / "set_bool_client.cpp", tmp_path / "set_bool_client")
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", "project_ros1.yaml", "--duration", "30"],
                              cwd=EXAMPLES / "set_bool", env=dict(env, PYTHONPATH=""), stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True)
    try:
        # (roscpp logs its waiting to stdout too: the answer is the last line)
        assert run_ros(env, str(client), "true", timeout=60).splitlines()[-1] == "success=true message=set to True"
        assert run_ros(env, str(client), "false", timeout=60).splitlines()[-1] == "success=false message=set to False"
    finally:
        stop(launch, 30)
