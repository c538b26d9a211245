"""`hetros init` finds every node of every shipped example, with the endpoints its project declares."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from hetros.project import template_from_sources

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
SECTIONS = ("publish", "subscribe", "services", "clients", "actions", "action_clients")


def _declared(example: Path) -> dict[str, dict[str, set[str]]]:
    """function of nodes.py -> section -> endpoint names, over every project file of the example."""
    found: dict[str, dict[str, set[str]]] = {}
    for project in sorted(example.glob("project*.yaml")):
        for spec in yaml.safe_load(project.read_text(encoding="utf-8")).get("nodes", {}).values():
            module, _, function = spec["run"].partition(":")
            if module != "nodes":
                continue
            entry = found.setdefault(function, {section: set() for section in SECTIONS})
            for section in SECTIONS:
                entry[section] |= set(spec.get(section, {}))
    return found


@pytest.mark.parametrize("example", sorted(p.parent.name for p in EXAMPLES.glob("*/nodes.py")))
def test_init_finds_every_node_and_endpoint_of_the_shipped_examples(example: str) -> None:
    folder = EXAMPLES / example
    template, unresolved = template_from_sources([folder / "nodes.py"], folder, example)
    declared = _declared(folder)
    assert set(template["nodes"]) == set(declared), unresolved
    for function, sections in declared.items():
        scanned = template["nodes"][function]
        for section in SECTIONS:
            assert set(scanned.get(section, {})) == sections[section], (function, section, unresolved)


def test_what_init_cannot_follow_is_named_with_file_and_line(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(
        "from hetros.interfaces.std_msgs.msg import String\n"
        "def relay(node, topic):\n"
        "    node.create_publisher(String, topic)\n"
        "def chooser(node):\n"
        "    node.create_subscription(String, node.get_parameter('topic'))\n"
        "def left(node):\n"
        "    relay(node, '/left')\n", encoding="utf-8")
    template, unresolved = template_from_sources([tmp_path / "nodes.py"], tmp_path, "t")
    assert set(template["nodes"]) == {"chooser", "left"}  # relay needs more than the node: a helper
    assert template["nodes"]["left"]["publish"] == {"/left": "std_msgs/msg/String"}
    assert unresolved == ["nodes.py:5: create_subscription(..., node.get_parameter('topic')) names its subscribe "
                          "endpoint at run time; add it to nodes.chooser.subscribe by hand"]
