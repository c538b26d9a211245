"""`kind: ros1` targets: hetros nodes that speak only ROS 1, with stock ROS 1 and with hetros nodes."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import time
from pathlib import Path

from hetros.project import load_project, plan
from hetros.project._graph import describe
from tests.support.ros1 import ROS_PYTHON, needs_ros1, run_ros, stop

NODES = textwrap.dedent('''
    from hetros.interfaces.std_msgs.msg import String
    from hetros.interfaces.std_srvs.srv import SetBool, Trigger

    def talker(node):
        pub = node.create_publisher(String, "/chatter")
        for i in node.rate(20):
            pub.publish(String(data=f"hello {i}"))

    def echo(node):
        pub = node.create_publisher(String, "/echoed")
        node.create_subscription(String, "/chatter", lambda m: pub.publish(String(data="echo " + m.data)))
        node.spin()

    def server(node):
        node.create_service(SetBool, "/set_bool",
                            lambda req: SetBool.Response(success=req.data, message=f"set to {req.data}"))
        node.spin()

    def _write(node, text):
        with open(node.get_parameter("out"), "a") as out:
            out.write(text + "\\n")

    def sink(node):
        for message in node.create_subscription(String, "/echoed"):
            _write(node, "sink " + message.data)

    def _call_forever(node, client, request, tag):
        while node.ok():
            try:
                reply = client.call(request, timeout=5.0)
            except Exception as exc:
                _write(node, f"{tag} error {type(exc).__name__}: {exc}")
            else:
                _write(node, f"{tag} {reply.success} {reply.message}")
            node.sleep(0.3)

    def caller(node):
        _call_forever(node, node.create_client(SetBool, "/set_bool"), SetBool.Request(data=True), "caller")

    def asker(node):
        _call_forever(node, node.create_client(Trigger, "/trigger"), Trigger.Request(), "asker")
''')

TRIGGER_SERVER = textwrap.dedent("""
    import rospy
    from std_srvs.srv import Trigger, TriggerResponse
    rospy.init_node("trigger_server")
    rospy.Service("/trigger", Trigger, lambda req: TriggerResponse(success=True, message="triggered by rospy"))
    rospy.spin()
""")


def _project(tmp_path: Path, uri: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    out = tmp_path / "out.txt"
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: ros1_targets
        targets: {{main: {{kind: thread}}, ros1a: {{kind: ros1}}, ros1b: {{kind: ros1}}}}
        nodes:
          talker: {{run: nodes:talker, target: ros1a, publish: {{/chatter: std_msgs/msg/String}}}}
          server: {{run: nodes:server, target: ros1a, services: {{/set_bool: std_srvs/srv/SetBool}}}}
          echo: {{run: nodes:echo, target: ros1b, subscribe: {{/chatter: std_msgs/msg/String}},
                 publish: {{/echoed: std_msgs/msg/String}}}}
          asker: {{run: nodes:asker, target: ros1b, clients: {{/trigger: std_srvs/srv/Trigger}},
                  parameters: {{out: {out}}}}}
          sink: {{run: nodes:sink, target: main, subscribe: {{/echoed: std_msgs/msg/String}},
                 parameters: {{out: {out}}}}}
          caller: {{run: nodes:caller, target: main, clients: {{/set_bool: std_srvs/srv/SetBool}},
                   parameters: {{out: {out}}}}}
        external:
          ros1: {{master: '{uri}'}}
    """))
    return tmp_path / "project.yaml"


def test_the_plan_keeps_ros1_nodes_out_of_the_hetros_channels_and_bridges_what_they_share(tmp_path: Path) -> None:
    planned = plan(load_project(_project(tmp_path, "http://127.0.0.1:11311/")))
    assert planned.speaks_ros1("talker") and not planned.speaks_ros1("sink")
    assert "/chatter" not in planned.channels  # ROS 1 node to ROS 1 node: TCPROS only
    bridge = planned.nodes["hetros_ros1_bridge"]
    assert bridge.publish == {"/echoed": "std_msgs/msg/String"}
    assert bridge.services == {"/set_bool": "std_srvs/srv/SetBool"}
    assert planned.process_of("talker") == "ros1a" and planned.process_of("echo") == "ros1b"
    text = describe(planned)
    assert "echo subscribes /chatter [std_msgs/msg/String]  via tcpros" in text
    assert "hetros_ros1_bridge -> sink  /echoed  via inproc" in text


@needs_ros1
def test_ros1_targets_talk_to_stock_ros1_and_to_hetros_nodes(ros_master: tuple[str, dict[str, str]],
                                                            tmp_path: Path) -> None:
    uri, env = ros_master
    (tmp_path / "trigger.py").write_text(TRIGGER_SERVER)
    trigger = subprocess.Popen([ROS_PYTHON, str(tmp_path / "trigger.py")], env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(_project(tmp_path, uri)),
                               "--duration", "40"], cwd=tmp_path,
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out = tmp_path / "out.txt"
    try:
        wanted = ("sink echo hello", "caller True set to True", "asker True triggered by rospy")
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            text = out.read_text() if out.exists() else ""
            if all(w in text for w in wanted):
                break
            time.sleep(0.2)
        assert all(w in text for w in wanted), text
        echoed = run_ros(env, ROS_PYTHON, "/usr/bin/rostopic", "echo", "-n", "2", "/echoed")
        assert "data: \"echo hello" in echoed
        # (a node with only clients registers nothing, so the master does not list it: as in ROS 1)
        nodes = run_ros(env, ROS_PYTHON, "/usr/bin/rosnode", "list").split()
        assert {"/talker", "/echo", "/server"} <= set(nodes), nodes
        called = run_ros(env, ROS_PYTHON, "/usr/bin/rosservice", "call", "/set_bool", "false")
        assert "success: False" in called and "set to False" in called
    finally:
        trigger.terminate()
        output = stop(launch, 30)
        stop(trigger)
    assert "Traceback" not in output, output
