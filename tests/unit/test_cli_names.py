"""The command line knows a node by its ROS name: the project's ``name:`` (and namespace), not its key."""

from __future__ import annotations

from pathlib import Path

from hetros.cli._inspect import ros_name
from hetros.project import plan_file


def test_a_nodes_name_is_its_name_on_the_command_line(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text("def listener(node):\n    pass\n")
    (tmp_path / "project.yaml").write_text(
        "name: names\nnodes:\n"
        "  listener: {run: nodes:listener, name: listener_remapped}\n"
        "  other: {run: nodes:listener, namespace: /r2}\n")
    plan = plan_file(tmp_path / "project.yaml")
    assert ros_name(plan, "listener") == "/listener_remapped"
    assert ros_name(plan, "other") == "/r2/other"
    assert "/listener_remapped/get_parameters" in plan.parameter_servers()
