"""ReconROS's sort demo as an action: a client sends arrays, a server sorts them and reports progress.

The server sorts by odd-even transposition (the hardware network of ReconROS's sorter,
one numpy step per phase) and publishes how many phases are done every ``feedback_every``
phases. It stops early when its goal is canceled. ``style: callback`` serves with an
``execute`` function, one thread per goal; ``style: thread`` is ReconROS's hardware-thread
shape, a loop that takes goals (``ROS_ACTIONSERVER_GOAL_TAKE``) and ends each one itself.
The client checks every result against ``numpy.sort``.
"""

import numpy as np

from hetros import GoalStatus, Node, ServerGoalHandle
from hetros.interfaces.sorter_msgs.action import Sort


def sort_phases(data: np.ndarray, first: int, last: int) -> None:
    """Run odd-even transposition phases ``first`` to ``last - 1`` on ``data`` in place."""
    n = data.size
    for phase in range(first, last):
        start = phase % 2
        stop = n - (n - start) % 2
        left, right = data[start:stop:2], data[start + 1:stop:2]
        low, high = np.minimum(left, right), np.maximum(left, right)
        data[start:stop:2], data[start + 1:stop:2] = low, high


def _sort_goal(node: Node, goal: ServerGoalHandle, every: int) -> Sort.Result | None:
    """Sort one goal's numbers with feedback; None when the goal was canceled on the way."""
    data = np.array(goal.request.unsorted, copy=True)
    for first in range(0, data.size, every):
        if goal.is_cancel_requested:
            node.log.info("goal canceled after %d of %d phases", first, data.size)
            return None
        sort_phases(data, first, min(first + every, data.size))
        goal.publish_feedback(Sort.Feedback(passes_done=min(first + every, data.size)))
    return Sort.Result(sorted=data)


def sorter(node: Node) -> None:
    every = node.get_parameter("feedback_every", 256)

    def accept(goal: Sort.Goal) -> bool:
        if len(goal.unsorted) == 0:
            node.log.warning("rejected a goal with nothing to sort")
            return False
        return True

    if node.get_parameter("style", "callback") == "callback":
        def execute(goal: ServerGoalHandle) -> Sort.Result | None:
            result = _sort_goal(node, goal, every)
            if result is None:
                goal.canceled()
            return result

        node.create_action_server(Sort, "/sort", execute, goal_callback=accept)
        return
    server = node.create_action_server(Sort, "/sort", goal_callback=accept)
    while node.ok():
        goal = server.take_goal()
        result = _sort_goal(node, goal, every)
        if result is None:
            server.canceled(goal)
        else:
            server.succeed(goal, result)


def client(node: Node) -> None:
    sort = node.create_action_client(Sort, "/sort")
    rng = np.random.default_rng(node.get_parameter("seed", 1))
    size = node.get_parameter("size", 2048)
    for run in range(node.get_parameter("runs", 3)):
        values = rng.integers(0, 2**32, size, dtype=np.uint32)
        progress: list[int] = []

        def record(feedback: Sort.Feedback, seen: list[int] = progress) -> None:  # this run's list, bound now
            seen.append(feedback.passes_done)

        goal = sort.send_goal(Sort.Goal(unsorted=values), feedback_cb=record)
        result = goal.result(timeout=60.0)
        if goal.status != GoalStatus.SUCCEEDED or not np.array_equal(result.sorted, np.sort(values)):
            raise ValueError(f"run {run}: the sorter's result ({goal.status.name}) differs from numpy.sort")
        if progress != sorted(progress) or progress[-1] != size:
            raise ValueError(f"run {run}: feedback out of order or incomplete: {progress}")
        node.log.info("run %d: %d numbers sorted correctly, %d feedback messages in order", run, size,
                      len(progress))
