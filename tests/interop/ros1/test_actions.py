"""Actions to and from stock ROS 1 actionlib (Debian's python3-actionlib) through `external: ros1:`.

The action is actionlib's own test action (``actionlib/Test``: goal, result and feedback an
int32 each), which rosbags' ROS 1 store and rospy both know; hetros declares it as a ROS 2
action in the project's message folder.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from hetros import CheckError
from hetros.msg import registry
from hetros.project import load_project, plan
from hetros.transport.tcpros import Ros1ActionType
from tests.support.ros1 import ROS_PYTHON, needs_ros1, stop


def _has_actionlib() -> bool:
    probe = subprocess.run([ROS_PYTHON, "-c", "import actionlib, actionlib.msg"], capture_output=True, check=False)
    return probe.returncode == 0


needs_actionlib = pytest.mark.skipif(not _has_actionlib(), reason="Debian's python3-actionlib is not installed "
                                                                  "(`make test` installs it when run as root)")

NODES = textwrap.dedent('''
    import time
    from hetros import GoalStatus
    from hetros.interfaces.actionlib.action import Test


    def server(node):
        def execute(goal):
            for step in range(goal.request.goal):
                if goal.is_cancel_requested:
                    node.log.info("hetros server: goal canceled after %d steps", step)
                    goal.canceled(Test.Result(result=-step))
                    return None
                goal.publish_feedback(Test.Feedback(feedback=step))
                time.sleep(0.02)
            return Test.Result(result=goal.request.goal * 10)

        node.create_action_server(Test, "/hetros_test", execute)


    def client(node):
        test = node.create_action_client(Test, "/ros1_test")
        seen = []
        goal = test.send_goal(Test.Goal(goal=4), feedback_cb=lambda f: seen.append(f.feedback))
        result = goal.result(timeout=30)
        node.log.info("from ROS 1: %s result %d feedback %s", goal.status.name, result.result, seen)
        seen = []
        goal = test.send_goal(Test.Goal(goal=1000), feedback_cb=lambda f: seen.append(f.feedback))
        while len(seen) < 3:
            time.sleep(0.01)
        goal.cancel()
        result = goal.result(timeout=30)
        node.log.info("from ROS 1 after cancel: %s", goal.status.name)
''')

ACTION = textwrap.dedent("""
    # actionlib's test action, as a ROS 2 .action file
    int32 goal
    ---
    int32 result
    ---
    int32 feedback
""")

ROS1_CLIENT = textwrap.dedent("""
    import rospy, actionlib
    from actionlib.msg import TestAction, TestGoal
    rospy.init_node("ros1_action_client")
    client = actionlib.SimpleActionClient("/hetros_test", TestAction)
    assert client.wait_for_server(rospy.Duration(30)), "no server"
    feedback = []
    client.send_goal(TestGoal(goal=5), feedback_cb=lambda f: feedback.append(f.feedback))
    assert client.wait_for_result(rospy.Duration(30))
    print("state", client.get_state(), "result", client.get_result().result, "feedback", feedback, flush=True)
    feedback = []
    client.send_goal(TestGoal(goal=1000), feedback_cb=lambda f: feedback.append(f.feedback))
    while len(feedback) < 3:
        rospy.sleep(0.01)
    client.cancel_goal()
    assert client.wait_for_result(rospy.Duration(30))
    print("canceled state", client.get_state(), "result", client.get_result().result, flush=True)
""")

ROS1_SERVER = textwrap.dedent("""
    import rospy, actionlib
    from actionlib.msg import TestAction, TestFeedback, TestResult
    rospy.init_node("ros1_action_server")

    def execute(goal):
        for step in range(goal.goal):
            if server.is_preempt_requested():
                server.set_preempted(TestResult(result=-1))
                return
            server.publish_feedback(TestFeedback(feedback=step))
            rospy.sleep(0.02)
        server.set_succeeded(TestResult(result=goal.goal + 100))

    server = actionlib.SimpleActionServer("/ros1_test", TestAction, execute, auto_start=False)
    server.start()
    rospy.spin()
""")


def _project(tmp_path: Path, ros1: str) -> Path:
    folder = tmp_path / "msg" / "actionlib" / "action"
    folder.mkdir(parents=True)
    (folder / "Test.action").write_text(ACTION)
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: actions_ros1
        messages: [msg]
        targets: {{main: {{kind: thread}}, worker: {{kind: process}}}}
        nodes:
          server: {{run: nodes:server, target: worker, actions: {{/hetros_test: actionlib/action/Test}}}}
          client: {{run: nodes:client, target: main,
                   action_clients: {{/ros1_test: actionlib/action/Test}}}}
        external:
          ros1: {ros1}
    """))
    return tmp_path / "project.yaml"


def test_the_actionlib_wrappers_hash_as_rospy_says(tmp_path: Path) -> None:
    """md5sums rospy's generated actionlib.msg carries (TestActionGoal, ...Result, ...Feedback)."""
    types = registry()
    types.load_folder(_folder_with_test_action(tmp_path))
    kind = Ros1ActionType(types, "actionlib/action/Test")
    assert kind.goal.name == "actionlib/TestActionGoal" and kind.goal.md5 == "348369c5b403676156094e8c159720bf"
    assert kind.result.md5 == "3d669e3a63aa986c667ea7b0f46ce85e"
    assert kind.feedback.md5 == "6d3d0bf7fb3dda24779c010a9f3eb7cb"
    assert kind.status.md5 == "8b2b82f13216d0a8ea88bd3af735e619"


def _folder_with_test_action(root: Path) -> Path:
    (root / "actionlib" / "action").mkdir(parents=True)
    (root / "actionlib" / "action" / "Test.action").write_text(ACTION)
    return root


@needs_ros1
@needs_actionlib
def test_actions_cross_to_and_from_stock_actionlib(ros_master: tuple[str, dict[str, str]], tmp_path: Path) -> None:
    uri, env = ros_master
    project = _project(tmp_path, f"{{master: '{uri}', export_actions: [/hetros_test], import_actions: [/ros1_test]}}")
    (tmp_path / "ros1_server.py").write_text(ROS1_SERVER)
    (tmp_path / "ros1_client.py").write_text(ROS1_CLIENT)
    ros1_server = subprocess.Popen([ROS_PYTHON, str(tmp_path / "ros1_server.py")], env=env,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "60"],
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        client = subprocess.run([ROS_PYTHON, str(tmp_path / "ros1_client.py")], env=env, capture_output=True,
                                text=True, timeout=90, check=False)
    finally:
        out = stop(launch, 60)
        stop(ros1_server)
    # a stock actionlib client drives a hetros server: SUCCEEDED = 3, PREEMPTED = 2
    assert "state 3 result 50 feedback [0, 1, 2, 3, 4]" in client.stdout, client.stdout + client.stderr + out
    assert "canceled state 2 result -" in client.stdout, client.stdout + client.stderr + out
    assert "hetros server: goal canceled after" in out, out
    # a hetros client drives a stock actionlib server
    assert "from ROS 1: SUCCEEDED result 104 feedback [0, 1, 2, 3]" in out, out
    assert "from ROS 1 after cancel: CANCELED" in out, out
    assert "Traceback" not in out, out


@pytest.mark.parametrize(("ros1", "expected"), [
    ("{export_actions: [/nothing]}", r"external\.ros1\.export_actions\.0.*/nothing has no hetros action server"),
    ("{import_actions: [/hetros_test]}", r"external\.ros1\.import_actions\.0.*/hetros_test is served by a hetros "
                                         r"node already"),
    ("{import_actions: [/elsewhere]}", r"external\.ros1\.import_actions\.0.*/elsewhere has no hetros action client"),
])
def test_bad_action_sharing_is_refused_by_check(tmp_path: Path, ros1: str, expected: str) -> None:
    with pytest.raises(CheckError, match=expected):
        plan(load_project(_project(tmp_path, ros1)))
