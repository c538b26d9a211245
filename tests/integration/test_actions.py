"""Actions end to end, launched from project files in both mappings (threads; processes over shm).

Feedback order, cancel during execution, two concurrent goals, a rejected goal, a server that
dies mid-goal and a client that dies mid-goal.
"""

from __future__ import annotations

import os
import queue
import re
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

NODES = textwrap.dedent('''
    import os, sys, time
    from hetros import ActionError, GoalRejectedError, GoalStatus, Node
    from hetros.interfaces.example_interfaces.action import Fibonacci


    def server(node: Node) -> None:
        delay = node.get_parameter("delay", 0.01)

        def execute(goal):
            order = goal.request.order
            node.log.info("executing goal of order %d in pid %d", order, os.getpid())
            sequence = [0, 1]
            for step in range(order):
                if goal.is_cancel_requested:
                    node.log.info("goal of order %d canceled after %d steps", order, step)
                    goal.canceled(Fibonacci.Result(sequence=sequence))
                    return None
                sequence.append((sequence[-1] + sequence[-2]) % 1_000_003)  # int32 for long goals
                goal.publish_feedback(Fibonacci.Feedback(sequence=sequence))
                time.sleep(delay)
            return Fibonacci.Result(sequence=sequence)

        node.create_action_server(Fibonacci, "/fib", execute, goal_callback=lambda goal: goal.order >= 0)


    def crashing_server(node: Node) -> None:
        server = node.create_action_server(Fibonacci, "/fib")
        goal = server.take_goal()
        node.log.info("executing goal of order %d in pid %d", goal.request.order, os.getpid())
        time.sleep(0.5)
        node.log.info("crashing at %.3f", time.time())
        raise RuntimeError("the server crashed mid-goal")


    def fib(order):
        sequence = [0, 1]
        for _ in range(order):
            sequence.append((sequence[-1] + sequence[-2]) % 1_000_003)
        return sequence


    def client(node: Node) -> None:
        fibonacci = node.create_action_client(Fibonacci, "/fib")

        # feedback in order, result complete
        seen = []
        goal = fibonacci.send_goal(Fibonacci.Goal(order=20), feedback_cb=lambda f: seen.append(list(f.sequence)))
        assert goal.accepted
        result = goal.result(timeout=30)
        assert goal.status == GoalStatus.SUCCEEDED, goal.status
        assert list(result.sequence) == fib(20)
        assert seen == [fib(n) for n in range(1, 21)], seen
        node.log.info("feedback in order: ok")

        # cancel during execution
        seen = []
        goal = fibonacci.send_goal(Fibonacci.Goal(order=2000), feedback_cb=lambda f: seen.append(len(f.sequence)))
        while len(seen) < 5:
            time.sleep(0.01)
        assert goal.cancel()
        result = goal.result(timeout=30)
        assert goal.status == GoalStatus.CANCELED, goal.status
        assert 5 <= len(result.sequence) < 2002
        assert not goal.cancel(), "an ended goal cannot be canceled again"
        node.log.info("cancel during execution: ok")

        # two goals at once: each one's feedback arrives while the other executes
        order = []
        first = fibonacci.send_goal(Fibonacci.Goal(order=40), feedback_cb=lambda f: order.append("a"))
        second = fibonacci.send_goal(Fibonacci.Goal(order=40), feedback_cb=lambda f: order.append("b"))
        assert list(first.result(timeout=30).sequence) == fib(40)
        assert list(second.result(timeout=30).sequence) == fib(40)
        assert order.count("a") == order.count("b") == 40
        assert order.index("b") < len(order) - 1 - order[::-1].index("a"), "the goals ran one after the other"
        node.log.info("two concurrent goals: ok")

        # a rejected goal
        goal = fibonacci.send_goal(Fibonacci.Goal(order=-1))
        assert not goal.accepted
        try:
            goal.result(timeout=5)
        except GoalRejectedError as exc:
            assert "rejected" in str(exc)
        else:
            raise AssertionError("a rejected goal has no result")
        node.log.info("rejected goal: ok")


    def waiting_client(node: Node) -> None:
        """Sends a long goal and reports how waiting for its result ends."""
        fibonacci = node.create_action_client(Fibonacci, "/fib")
        goal = fibonacci.send_goal(Fibonacci.Goal(order=100000))
        node.log.info("client pid %d waits", os.getpid())
        try:
            goal.result(timeout=50)
        except ActionError as exc:
            node.log.info("action error at %.3f: %s", time.time(), exc)


    def crashing_client(node: Node) -> None:
        fibonacci = node.create_action_client(Fibonacci, "/fib")
        fibonacci.send_goal(Fibonacci.Goal(order=100000))
        time.sleep(0.5)
        raise RuntimeError("the client crashed mid-goal")
''')


def _project(tmp_path: Path, mapping: str, server: str = "server", client: str = "client") -> Path:
    (tmp_path / "action_nodes.py").write_text(NODES)
    if mapping == "threads":
        targets = "targets: {main: {kind: thread}}"
        where = ("main", "main")
    else:
        targets = "targets: {server_proc: {kind: process}, client_proc: {kind: process}}"
        where = ("server_proc", "client_proc")
    project = tmp_path / f"{mapping}.yaml"
    project.write_text(textwrap.dedent(f"""
        name: actions_{mapping}
        {targets}
        nodes:
          fib_server: {{run: "action_nodes:{server}", target: {where[0]},
                       actions: {{/fib: example_interfaces/action/Fibonacci}}}}
          fib_client: {{run: "action_nodes:{client}", target: {where[1]}, required: true,
                       action_clients: {{/fib: example_interfaces/action/Fibonacci}}}}
    """))
    return project


class _Launch:
    """`hetros launch` with its log lines readable as they come."""

    def __init__(self, project: Path) -> None:
        self.proc = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", "60"],
                                     stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line)

    def expect(self, pattern: str, timeout: float = 60) -> re.Match[str]:
        """The first line matching ``pattern``, among those printed so far or still to come."""
        for line in self.seen:
            if match := re.search(pattern, line):
                return match
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self.lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                printed = "".join(self.seen)
                raise AssertionError(f"no line matching {pattern!r}; the launch printed:\n{printed}") from None
            self.seen.append(line)
            match = re.search(pattern, line)
            if match:
                return match

    def finish(self) -> str:
        try:
            self.proc.wait(60)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        while not self.lines.empty():
            self.seen.append(self.lines.get())
        time.sleep(0.1)
        while not self.lines.empty():
            self.seen.append(self.lines.get())
        return "".join(self.seen)


MAPPINGS = ["threads", "processes"]


@pytest.mark.parametrize("mapping", MAPPINGS)
def test_feedback_cancel_concurrent_goals_and_rejection(tmp_path: Path, mapping: str) -> None:
    result = subprocess.run([sys.executable, "-m", "hetros", "launch", str(_project(tmp_path, mapping)),
                             "--duration", "90"], capture_output=True, text=True, timeout=150, check=False)
    for check in ("feedback in order", "cancel during execution", "two concurrent goals", "rejected goal"):
        assert f"{check}: ok" in result.stderr, result.stderr
    assert result.returncode == 0, result.stderr
    assert re.search(r"goal of order 2000 canceled after \d+ steps", result.stderr)


def test_a_killed_server_process_fails_the_waiting_client_within_a_second(tmp_path: Path) -> None:
    launch = _Launch(_project(tmp_path, "processes", client="waiting_client"))
    try:
        pid = int(launch.expect(r"executing goal of order 100000 in pid (\d+)").group(1))
        launch.expect(r"client pid \d+ waits")
        killed_at = time.time()
        os.kill(pid, signal.SIGKILL)
        error = launch.expect(r"action error at ([\d.]+): (.*)")
    finally:
        output = launch.finish()
    assert float(error.group(1)) - killed_at < 1.0, output
    message = error.group(2)
    assert "/fib" in message and "target server_proc died" in message and "fib_server" in message, message
    assert "SIGKILL" in message


def test_a_server_node_that_raises_mid_goal_fails_the_waiting_client_within_a_second(tmp_path: Path) -> None:
    launch = _Launch(_project(tmp_path, "threads", server="crashing_server", client="waiting_client"))
    try:
        crashed_at = float(launch.expect(r"crashing at ([\d.]+)").group(1))
        error = launch.expect(r"action error at ([\d.]+): (.*)")
    finally:
        output = launch.finish()
    assert float(error.group(1)) - crashed_at < 1.0, output
    assert "/fib" in error.group(2) and "node fib_server failed" in error.group(2), error.group(2)


@pytest.mark.parametrize("mapping", MAPPINGS)
def test_a_client_that_dies_mid_goal_leaves_the_server_goal_canceled(tmp_path: Path, mapping: str) -> None:
    if mapping == "threads":
        launch = _Launch(_project(tmp_path, mapping, client="crashing_client"))
    else:
        launch = _Launch(_project(tmp_path, mapping, client="waiting_client"))
    try:
        launch.expect(r"executing goal of order 100000")
        if mapping == "processes":
            pid = int(launch.expect(r"client pid (\d+) waits").group(1))
            os.kill(pid, signal.SIGKILL)
        launch.expect(r"goal of order 100000 canceled after \d+ steps", timeout=20)
    finally:
        output = launch.finish()
    assert "did not stop" not in output, output
    assert launch.proc.returncode == 1, output  # the client's death is reported, not hidden
