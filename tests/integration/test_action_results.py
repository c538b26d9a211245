"""An action's result follows rclpy's contract, across threads and across processes.

The execute callback's return value is the goal's result whether or not it called
``succeed()``/``abort()``/``canceled()`` first (ros2/examples' minimal action server calls
``goal_handle.succeed()`` and then returns the result; the result used to arrive empty).
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

NODES = textwrap.dedent('''
    import time
    from hetros import ActionError, GoalStatus, Node
    from hetros.interfaces.example_interfaces.action import Fibonacci
    from hetros.interfaces.std_msgs.msg import String


    def server(node: Node) -> None:
        def execute(goal):
            mode = goal.request.order
            if mode == 1:  # ros2/examples' minimal action server: succeed(), then return the result
                sequence = [0, 1]
                for _ in range(5):
                    sequence.append(sequence[-1] + sequence[-2])
                    goal.publish_feedback(Fibonacci.Feedback(sequence=sequence))
                    time.sleep(0.02)
                goal.succeed()
                return Fibonacci.Result(sequence=sequence)
            if mode == 2:  # succeed(result), nothing returned
                goal.succeed(Fibonacci.Result(sequence=[2]))
                return None
            if mode == 3:  # abort(), then the result
                goal.abort()
                return Fibonacci.Result(sequence=[3])
            if mode == 4:  # canceled() once a cancel came, then the result
                while not goal.is_cancel_requested:
                    time.sleep(0.005)
                goal.canceled()
                return Fibonacci.Result(sequence=[4])
            if mode == 5:  # only a return
                return Fibonacci.Result(sequence=[5])
            if mode == 6:  # the wrong type
                return String(data="not a result")
            if mode == 7:  # ended twice: the second is an error, the first stands
                goal.succeed()
                try:
                    goal.abort()
                except ActionError as exc:
                    node.log.info("ended twice refused: %s", exc)
                return Fibonacci.Result(sequence=[7])
            if mode == 8:  # succeed(result) and a return: the return wins, as in rclpy
                goal.succeed(Fibonacci.Result(sequence=[1]))
                return Fibonacci.Result(sequence=[8])
            raise ValueError(mode)

        node.create_action_server(Fibonacci, "/fib", execute)


    def client(node: Node) -> None:
        fib = node.create_action_client(Fibonacci, "/fib")
        expected = {1: (GoalStatus.SUCCEEDED, [0, 1, 1, 2, 3, 5, 8]), 2: (GoalStatus.SUCCEEDED, [2]),
                    3: (GoalStatus.ABORTED, [3]), 5: (GoalStatus.SUCCEEDED, [5]), 6: (GoalStatus.ABORTED, []),
                    7: (GoalStatus.SUCCEEDED, [7]), 8: (GoalStatus.SUCCEEDED, [8])}
        for mode, (status, sequence) in expected.items():
            goal = fib.send_goal(Fibonacci.Goal(order=mode))
            result = goal.result(timeout=20)
            assert (goal.status, list(result.sequence)) == (status, sequence), (mode, goal.status, result)
            node.log.info("mode %d: ok", mode)
        goal = fib.send_goal(Fibonacci.Goal(order=4))
        time.sleep(0.1)
        assert goal.cancel()
        result = goal.result(timeout=20)
        assert (goal.status, list(result.sequence)) == (GoalStatus.CANCELED, [4]), (goal.status, result)
        node.log.info("mode 4: ok")
        # concurrent goals of the minimal server pattern: each gets its own result
        goals = [fib.send_goal(Fibonacci.Goal(order=1)) for _ in range(3)]
        results = [list(g.result(timeout=20).sequence) for g in goals]
        assert results == [[0, 1, 1, 2, 3, 5, 8]] * 3, results
        node.log.info("concurrent: ok")
''')


@pytest.mark.parametrize("mapping", ["threads", "processes"])
def test_the_execute_callbacks_return_value_is_the_result(tmp_path: Path, mapping: str) -> None:
    (tmp_path / "result_nodes.py").write_text(NODES)
    if mapping == "threads":
        targets, where = "{main: {kind: thread}}", ("main", "main")
    else:
        targets, where = "{s: {kind: process}, c: {kind: process}}", ("s", "c")
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: results_{mapping}
        targets: {targets}
        nodes:
          fib_server: {{run: "result_nodes:server", target: {where[0]},
                       actions: {{/fib: example_interfaces/action/Fibonacci}}}}
          fib_client: {{run: "result_nodes:client", target: {where[1]}, required: true,
                       action_clients: {{/fib: example_interfaces/action/Fibonacci}}}}
    """))
    proc = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                           "--duration", "60"], capture_output=True, text=True, timeout=120)
    for mode in (1, 2, 3, 4, 5, 6, 7, 8):
        assert f"mode {mode}: ok" in proc.stderr, proc.stderr[-4000:]
    assert "concurrent: ok" in proc.stderr, proc.stderr[-4000:]
    assert "ended twice refused" in proc.stderr and "a goal ends once" in proc.stderr
    # the wrong type is named with the action
    assert "the result of action /fib" in proc.stderr, proc.stderr[-4000:]
    assert proc.returncode == 0, proc.stderr[-4000:]
