"""An action across ROS 2's wire: one graph exports its server, another imports it, and the
goal, feedback, cancel and result travel as ROS 2's three services and two topics on DDS."""

from __future__ import annotations

import textwrap
from pathlib import Path

from hetros.plan import action_endpoints
from hetros.transport.dds import dds_type_name, reply_topic, request_topic, topic_name
from tests.support.ros2 import free_domain, launched, wait_for, write_project

MSG = Path(__file__).resolve().parents[3] / "examples" / "sort_action" / "msg"

CLIENT = textwrap.dedent('''
    import numpy as np
    from hetros import GoalStatus
    from hetros.interfaces.sorter_msgs.action import Sort

    def client(node):
        sort = node.create_action_client(Sort, "/sort")
        values = np.arange(512, 0, -1, dtype=np.uint32)
        progress = []
        goal = sort.send_goal(Sort.Goal(unsorted=values), feedback_cb=lambda f: progress.append(f.passes_done))
        result = goal.result(timeout=60)
        lines = [f"first {goal.status.name} {bool(np.array_equal(result.sorted, np.sort(values)))} "
                 f"{progress == sorted(progress) and progress[-1] == 512}"]
        slow = sort.send_goal(Sort.Goal(unsorted=np.arange(20000, 0, -1, dtype=np.uint32)),
                              feedback_cb=lambda f: None)
        slow.cancel()
        slow.result(timeout=60)
        lines.append(f"second {slow.status.name}")
        with open(node.get_parameter("out"), "w") as out:
            out.write("\\n".join(lines) + "\\n")
''')


def test_an_action_crosses_ros2_with_feedback_cancel_and_result(tmp_path: Path) -> None:
    domain = free_domain()
    sorter_dir = Path(__file__).resolve().parents[3] / "examples" / "sort_action"
    server_project = write_project(tmp_path / "server", (sorter_dir / "nodes.py").read_text(), f"""
        name: sort_server
        messages: [{MSG}]
        targets: {{proc: {{kind: process}}}}
        nodes:
          sorter: {{run: nodes:sorter, target: proc, actions: {{/sort: sorter_msgs/action/Sort}},
                   parameters: {{style: callback, feedback_every: 64}}}}
        external:
          ros2: {{domain: {domain}, export_actions: [/sort]}}
    """)
    client_dir = tmp_path / "client"
    client_project = write_project(client_dir, CLIENT, f"""
        name: sort_client
        messages: [{MSG}]
        targets: {{proc: {{kind: process}}}}
        nodes:
          client: {{run: nodes:client, target: proc, action_clients: {{/sort: sorter_msgs/action/Sort}},
                   parameters: {{out: {client_dir / "got.txt"}}}}}
        external:
          ros2: {{domain: {domain}, import_actions: [/sort]}}
    """)
    got = client_dir / "got.txt"
    with launched(server_project, duration=60) as server, launched(client_project, duration=60) as client:
        try:
            wait_for(got.exists, 60, "the client's outcome")
        except AssertionError:
            for process in (client, server):
                process.terminate()
            raise AssertionError(f"client:\n{client.communicate()[0]}\nserver:\n{server.communicate()[0]}") from None
        lines = wait_for(lambda: len(got.read_text().splitlines()) == 2 and got.read_text().splitlines(), 10,
                         "both outcomes")
    assert lines == ["first SUCCEEDED True True", "second CANCELED"], lines


def test_an_actions_dds_names_are_ros2s() -> None:
    services, topics = action_endpoints("/sort", "sorter_msgs/action/Sort")
    assert sorted(request_topic(s) for s in services) == [
        "rq/sort/_action/cancel_goalRequest", "rq/sort/_action/get_resultRequest", "rq/sort/_action/send_goalRequest"]
    assert sorted(reply_topic(s) for s in services) == [
        "rr/sort/_action/cancel_goalReply", "rr/sort/_action/get_resultReply", "rr/sort/_action/send_goalReply"]
    assert sorted(topic_name(t) for t in topics) == ["rt/sort/_action/feedback", "rt/sort/_action/status"]
    assert dds_type_name(services["/sort/_action/send_goal"] + "_Request") == \
        "sorter_msgs::action::dds_::Sort_SendGoal_Request_"
    assert dds_type_name(topics["/sort/_action/feedback"]) == "sorter_msgs::action::dds_::Sort_FeedbackMessage_"
    assert dds_type_name(topics["/sort/_action/status"]) == "action_msgs::msg::dds_::GoalStatusArray_"
    assert dds_type_name(services["/sort/_action/cancel_goal"] + "_Response") == \
        "action_msgs::srv::dds_::CancelGoal_Response_"
