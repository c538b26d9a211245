"""A parameter the code passes to a rate or a timer: check refuses what the launch would refuse at that call
('fast', NaN, 0, -5, 1e-320, a bool), naming the YAML path and the code's line; the runtime refuses the same
values where code computes them."""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from hetros import Node, NodeError
from hetros.project import check, load_project
from hetros.runtime import Graph

CODE = textwrap.dedent("""
    from hetros.interfaces.std_msgs.msg import String


    def talker(node):
        for _ in node.rate(node.get_parameter("hz", 10.0)):
            pass


    def ticker(node):
        period = node.get_parameter("period")
        node.create_timer(period, lambda: None)
""")


@pytest.mark.parametrize("value", ["fast", ".nan", "0", "-5", "1e-320", "true", "[1, 2]", ".inf"])
def test_check_refuses_what_a_rate_or_timer_cannot_take(value: str, tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(CODE)
    for node, parameter, call in (("talker", "hz", "rate"), ("ticker", "period", "create_timer")):
        (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
            name: timing
            nodes:
              {node}: {{run: nodes:{node}, parameters: {{{parameter}: {value}}}}}
        """))
        errors = check(load_project(tmp_path / "project.yaml")).errors
        assert any(re.match(rf"\S*project.yaml:4: nodes\.{node}\.parameters\.{parameter}: the code of {node} "
                            rf"\(nodes.py:\d+\) passes {parameter} to {call}\(\)", e) for e in errors), errors
    (tmp_path / "project.yaml").write_text(
        "name: timing\nnodes:\n  talker: {run: nodes:talker, parameters: {hz: 30}}\n")
    assert not check(load_project(tmp_path / "project.yaml")).errors


@pytest.mark.parametrize("value", [float("nan"), 0, -5.0, 1e-320, float("inf"), "fast", True])
def test_the_runtime_refuses_the_same_values(value: object) -> None:
    node = Node("n", Graph.standalone())
    try:
        with pytest.raises(NodeError, match="rate"):
            next(node.rate(value))  # type: ignore[arg-type]
        with pytest.raises(NodeError, match="period"):
            node.create_timer(value, lambda: None)  # type: ignore[arg-type]
    finally:
        node.graph.shutdown()
