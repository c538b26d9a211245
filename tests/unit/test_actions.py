"""The action state machine in one process: cancel policies, goal bounds, late results, misuse."""

from __future__ import annotations

import textwrap
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hetros import (
    ActionError,
    ActionTimeoutError,
    GoalStatus,
    Node,
    NodeError,
    ServerGoalHandle,
    TopicTypeError,
    UndeclaredEndpointError,
)
from hetros.interfaces.action_msgs.msg import GoalInfo
from hetros.interfaces.builtin_interfaces.msg import Time
from hetros.interfaces.example_interfaces.action import Fibonacci
from hetros.interfaces.std_msgs.msg import String
from hetros.interfaces.unique_identifier_msgs.msg import UUID
from hetros.project import check, import_reconros, load_project, plan, template_from_sources
from hetros.runtime import Graph


@pytest.fixture
def graph() -> Iterator[Graph]:
    graph = Graph.standalone()
    yield graph
    graph.shutdown()


def _until(condition: Any, timeout: float = 5.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, "condition never held"
        time.sleep(0.005)


class Gate:
    """An execute callback that holds each goal until released (or canceled)."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.running = 0
        self.most = 0
        self.lock = threading.Lock()

    def __call__(self, goal: ServerGoalHandle) -> Any:
        with self.lock:
            self.running += 1
            self.most = max(self.most, self.running)
        try:
            while not self.release.wait(0.005):
                if goal.is_cancel_requested:
                    goal.canceled()
                    return None
            return Fibonacci.Result(sequence=[goal.request.order])
        finally:
            with self.lock:
                self.running -= 1


def _pair(graph: Graph, execute: Any = None, **server_options: Any) -> tuple[Any, Any]:
    server = Node("server", graph).create_action_server(Fibonacci, "/fib", execute, **server_options)
    client = Node("client", graph).create_action_client(Fibonacci, "/fib")
    return server, client


def test_goals_beyond_max_goals_wait_accepted_until_a_slot_frees(graph: Graph) -> None:
    gate = Gate()
    server, client = _pair(graph, gate, max_goals=2)
    handles = [client.send_goal(Fibonacci.Goal(order=n)) for n in range(4)]
    _until(lambda: gate.running == 2)
    time.sleep(0.05)
    assert gate.running == 2
    states = sorted(g.status for g in server.goals)
    assert states == [GoalStatus.ACCEPTED, GoalStatus.ACCEPTED, GoalStatus.EXECUTING, GoalStatus.EXECUTING]
    gate.release.set()
    assert [list(h.result(timeout=5).sequence) for h in handles] == [[0], [1], [2], [3]]
    assert gate.most == 2
    assert all(h.status == GoalStatus.SUCCEEDED for h in handles)


def test_a_finished_goal_result_is_kept_for_a_late_get_result(graph: Graph) -> None:
    _server, client = _pair(graph, lambda goal: Fibonacci.Result(sequence=[7, goal.request.order]))
    handle = client.send_goal(Fibonacci.Goal(order=3))
    assert list(handle.result(timeout=5).sequence) == [7, 3]
    late = client._get_result.call(Fibonacci.GetResult.Request(goal_id=UUID(uuid=np.frombuffer(handle.goal_id,
                                                                                              np.uint8).copy())))
    assert late.status == GoalStatus.SUCCEEDED and list(late.result.sequence) == [7, 3]
    unknown = client._get_result.call(Fibonacci.GetResult.Request(goal_id=UUID(uuid=np.ones(16, np.uint8))))
    assert unknown.status == GoalStatus.UNKNOWN


def _cancel(client: Any, goal_id: bytes = bytes(16), stamp: Any = None) -> Any:
    info = GoalInfo(goal_id=UUID(uuid=np.frombuffer(goal_id, np.uint8).copy()), stamp=stamp or Time())
    return client._cancel_goal.call(client._cancel_goal.srv_type.Request(goal_info=info))


def test_cancel_policies_follow_ros2(graph: Graph) -> None:
    gate = Gate()
    _server, client = _pair(graph, gate)
    first, second = client.send_goal(Fibonacci.Goal(order=1)), client.send_goal(Fibonacci.Goal(order=2))
    _until(lambda: gate.running == 2)
    response = _cancel(client, bytes(range(16)))
    assert response.return_code == 2 and len(response.goals_canceling) == 0  # unknown goal id
    by_stamp = _cancel(client, stamp=first.stamp)  # zero id + stamp: goals accepted at or before it
    assert {bytes(g.goal_id.uuid) for g in by_stamp.goals_canceling} == {first.goal_id}
    assert first.result(timeout=5) is not None and first.status == GoalStatus.CANCELED
    everything = _cancel(client)  # zero id, zero stamp: every goal
    assert [bytes(g.goal_id.uuid) for g in everything.goals_canceling] == [second.goal_id]
    second.result(timeout=5)
    assert second.status == GoalStatus.CANCELED
    terminated = _cancel(client, second.goal_id)
    assert terminated.return_code == 3 and not terminated.goals_canceling  # already ended


def test_a_cancel_callback_may_refuse(graph: Graph) -> None:
    gate = Gate()
    _server, client = _pair(graph, gate, cancel_callback=lambda goal: False)
    handle = client.send_goal(Fibonacci.Goal(order=1))
    _until(lambda: gate.running == 1)
    assert not handle.cancel()
    gate.release.set()
    handle.result(timeout=5)
    assert handle.status == GoalStatus.SUCCEEDED


def test_an_execute_that_raises_aborts_its_goal_and_the_server_goes_on(graph: Graph,
                                                                      caplog: pytest.LogCaptureFixture) -> None:
    def execute(goal: ServerGoalHandle) -> Any:
        if goal.request.order < 0:
            raise ValueError("negative order")
        return Fibonacci.Result(sequence=[1])

    _server, client = _pair(graph, execute)
    bad = client.send_goal(Fibonacci.Goal(order=-1))
    bad.result(timeout=5)
    assert bad.status == GoalStatus.ABORTED
    assert "negative order" in caplog.text
    good = client.send_goal(Fibonacci.Goal(order=1))
    assert list(good.result(timeout=5).sequence) == [1] and good.status == GoalStatus.SUCCEEDED


def test_thread_style_take_goal_and_status_topic(graph: Graph) -> None:
    server, client = _pair(graph)
    watcher = Node("watcher", graph).create_subscription(
        graph.types.get("action_msgs/msg/GoalStatusArray"), "/fib/_action/status")
    with pytest.raises(ActionTimeoutError, match=r"no goal for action /fib within 0\.05 s"):
        server.take_goal(timeout=0.05)
    handle = client.send_goal(Fibonacci.Goal(order=5))
    goal = server.take_goal(timeout=5)
    assert goal.request.order == 5 and goal.status == GoalStatus.EXECUTING
    with pytest.raises(ActionError, match="not canceling"):
        server.canceled(goal)
    with pytest.raises(TopicTypeError, match="Fibonacci_Feedback"):
        server.publish_feedback(goal, String(data="wrong"))
    server.succeed(goal, Fibonacci.Result(sequence=[5]))
    with pytest.raises(ActionError, match="already ended"):
        server.succeed(goal, Fibonacci.Result())
    assert list(handle.result(timeout=5).sequence) == [5]
    states = []
    while (message := watcher.try_take()) is not None:
        states.append([s.status for s in message.status_list])
    assert states[-1] == [GoalStatus.SUCCEEDED]


def test_closing_the_server_cancels_then_aborts_running_goals(graph: Graph) -> None:
    stubborn = threading.Event()

    def execute(goal: ServerGoalHandle) -> Any:
        while not goal.is_cancel_requested:
            time.sleep(0.005)
        stubborn.set()
        return None  # left without canceled(): a requested cancel ends it canceled

    server, client = _pair(graph, execute)
    handle = client.send_goal(Fibonacci.Goal(order=1))
    _until(lambda: any(g.status == GoalStatus.EXECUTING for g in server.goals))
    server.close()
    assert stubborn.is_set()
    handle.result(timeout=5)
    assert handle.status == GoalStatus.CANCELED


def test_wrong_goal_type_and_wrong_action_type_are_refused(graph: Graph) -> None:
    _server, client = _pair(graph, lambda goal: Fibonacci.Result())
    with pytest.raises(TopicTypeError, match="a goal of action /fib carries example_interfaces/action/Fibonacci_Goal"):
        client.send_goal(String(data="x"))
    with pytest.raises(TopicTypeError, match="hetros action type"):
        Node("other", graph).create_action_client(Fibonacci.Goal, "/fib")  # type: ignore[arg-type]
    with pytest.raises(NodeError, match="already has a client of action /fib"):
        client.node.create_action_client(Fibonacci, "/fib")


NODES = textwrap.dedent('''
    from hetros.interfaces.example_interfaces.action import Fibonacci

    def server(node):
        node.create_action_server(Fibonacci, "/fib", lambda goal: Fibonacci.Result())

    def client(node):
        node.create_action_client(Fibonacci, "/fib")
''')


def _project(tmp_path: Path, nodes: str) -> Path:
    (tmp_path / "nodes.py").write_text(NODES)
    path = tmp_path / "project.yaml"
    path.write_text("name: t\ntargets: {a: {kind: process}, b: {kind: thread}}\nnodes:\n" + textwrap.indent(
        textwrap.dedent(nodes), "  "))
    return path


def test_check_validates_actions_like_services(tmp_path: Path) -> None:
    path = _project(tmp_path, """
        server: {run: "nodes:server", target: a, actions: {/fib: example_interfaces/action/Fibonaci}}
        client: {run: "nodes:client", target: b, action_clients: {/fob: example_interfaces/Fibonacci}}
        other: {run: "nodes:server", target: b, actions: {"/x/_action/y": example_interfaces/Fibonacci}}
    """)
    errors = "\n".join(check(load_project(path)).errors)
    assert "nodes.server.actions./fib: unknown action type 'example_interfaces/action/Fibonaci'" in errors
    assert "nodes.client.action_clients./fob: no node serves action /fob; add it under some node's 'actions'" in errors
    assert "nodes.other.actions./x/_action/y: an action name cannot contain '/_action'" in errors
    assert "project does not declare" in errors  # other's code creates /fib, declared is /x/_action/y


def test_an_action_plans_as_three_services_and_two_topics_per_mapping(tmp_path: Path) -> None:
    path = _project(tmp_path, """
        server: {run: "nodes:server", target: a, actions: {/fib: {type: example_interfaces/Fibonacci, max_goals: 3}}}
        client: {run: "nodes:client", target: b, action_clients: {/fib: example_interfaces/action/Fibonacci}}
    """)
    planned = plan(load_project(path))
    assert planned.nodes["server"].actions == {"/fib": "example_interfaces/action/Fibonacci"}
    assert planned.nodes["server"].max_goals == {"/fib": 3}
    names = {e.channel: e.transport for e in planned.edges}
    assert names == {
        "/fib/_action/feedback": "shm", "/fib/_action/status": "shm",
        "/fib/_action/send_goal/_request": "shm", "/fib/_action/cancel_goal/_request": "shm",
        "/fib/_action/get_result/_request": "shm", "/fib/_action/send_goal/_reply/client": "shm",
        "/fib/_action/cancel_goal/_reply/client": "shm", "/fib/_action/get_result/_reply/client": "shm",
    }
    assert planned.channels["/fib/_action/status"].qos.keeps_history
    assert planned.channels["/fib/_action/feedback"].qos.blocks_publisher


def test_an_undeclared_action_names_the_yaml_key_to_add(tmp_path: Path) -> None:
    path = _project(tmp_path, """
        server: {run: "nodes:server", target: b, actions: {/fib: example_interfaces/Fibonacci}}
        client: {run: "nodes:client", target: b, action_clients: {/fib: example_interfaces/Fibonacci}}
    """)
    graph = Graph(plan(load_project(path)))
    try:
        with pytest.raises(UndeclaredEndpointError, match=r"add `/other: example_interfaces/action/Fibonacci` "
                                                           r"under nodes.server.actions"):
            Node("server", graph).create_action_server(Fibonacci, "/other", lambda goal: None)
    finally:
        graph.shutdown()
        graph.close()


def test_init_and_reconros_import_pick_up_actions(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(NODES)
    template, _ = template_from_sources([tmp_path / "nodes.py"], tmp_path, "t")
    assert template["nodes"]["server"]["actions"] == {"/fib": "example_interfaces/action/Fibonacci"}
    assert template["nodes"]["client"]["action_clients"] == {"/fib": "example_interfaces/action/Fibonacci"}
    cfg = tmp_path / "build.cfg"
    cfg.write_text(textwrap.dedent("""
        [ResourceGroup@Server]
        sort_action = rosactionmsg, sorter_msgs, action, Sort
        node_1 = rosnode, "sorter"
        serve = rosactions, node_1, sort_action, "sort", 10000
        [ResourceGroup@Client]
        sort_action = rosactionmsg, sorter_msgs, action, Sort
        node_2 = rosnode, "caller"
        call = rosactionc, node_2, sort_action, "sort", 10000
    """))
    data, _ = import_reconros(cfg)
    assert data["nodes"]["sorter"]["actions"] == {"/sort": "sorter_msgs/action/Sort"}
    assert data["nodes"]["caller"]["action_clients"] == {"/sort": "sorter_msgs/action/Sort"}


def test_a_goal_sent_and_awaited_inside_a_callback_completes(graph: Graph) -> None:
    """As with service calls: the client waits on its own replies, not on the node's callback queue."""
    from hetros.interfaces.std_msgs.msg import Int32

    _pair(graph, lambda goal: Fibonacci.Result(sequence=[goal.request.order * 2]))
    node = Node("caller", graph)
    client = node.create_action_client(Fibonacci, "/fib")
    results: list[list[int]] = []

    def on_trigger(message: Any) -> None:
        goal = client.send_goal(Fibonacci.Goal(order=message.data))
        results.append([int(v) for v in goal.result(timeout=5).sequence])

    node.create_subscription(Int32, "/trigger", on_trigger)
    spinner = threading.Thread(target=node.spin, daemon=True)
    spinner.start()
    trigger = Node("trigger", graph).create_publisher(Int32, "/trigger")
    trigger.publish(Int32(data=21))
    _until(lambda: results == [[42]])
