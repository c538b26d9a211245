"""The rules of `hetros check`, one by one, the one-edge-one-transport rule, and the system nodes' table.

Each rule in ``project._checks.RULES`` is shown reporting on a project made to break it (and that
rule, not another, is the one that reports). ``edge_transport`` is held to hand-made placements.
``plan.SYSTEM_NODES`` names code by dotted strings the layer test cannot see: each must resolve.
"""

from __future__ import annotations

import importlib
import textwrap
from pathlib import Path

import pytest

from hetros.msg import registry
from hetros.plan import ROS1_BRIDGE, SYSTEM_NODES
from hetros.project import load_project
from hetros.project._bridges import bridged, ros1_nodes
from hetros.project._checks import RULES, CheckContext, load_messages
from hetros.project._planner import Placement, edge_transport
from hetros.project._report import CheckReport

HEAD = "name: rules\ntargets: {main: {kind: thread}, p: {kind: process}, f: {kind: fpga}}\n"
STRING = "std_msgs/msg/String"
CASES = Path(__file__).resolve().parents[1] / "cases"

BROKEN = {
    "cpus_exist": "targets: {main: {kind: process, cpus: [4096]}}\nnodes: {a: {run: json:dumps, target: main}}",
    "bridge_names_reserved": f"nodes: {{{ROS1_BRIDGE}: {{run: json:dumps, target: main}}}}",
    "import_folders_exist": "python_path: [no_such_folder]\nnodes: {a: {run: json:dumps, target: main}}",
    "nodes_are_well_formed": "nodes: {a: {run: json:dumps, target: nowhere}}",
    "gather_endpoints": "nodes: {a: {run: json:dumps, target: main, publish: {/x: std_msgs/msg/Nothing}}}",
    "code_runs": "nodes: {a: {run: json:nobody_here, target: main}}",
    "code_qos_agrees": (f"python_path: [{CASES}]\nnodes: {{a: {{run: qos_choice_module:main, target: main, "
                        f"publish: {{/x: {STRING}}}}}}}\ntopics: {{/x: {{reliability: reliable}}}}"),
    "subscriptions_have_publishers": f"nodes: {{a: {{run: json:dumps, target: main, subscribe: {{/x: {STRING}}}}}}}",
    "one_type_per_topic": (f"nodes: {{a: {{run: json:dumps, target: main, publish: {{/x: {STRING}}}}},\n"
                           "        b: {run: json:dumps, target: main, subscribe: {/x: std_msgs/msg/Int32}}}"),
    "clients_have_servers": "nodes: {a: {run: json:dumps, target: main, clients: {/s: std_srvs/srv/Trigger}}}",
    "one_server_one_type_per_service": ("nodes: {a: {run: json:dumps, target: main, services: {/s: std_srvs/srv/"
                                        "Trigger}},\n        b: {run: json:dumps, target: main, services: {/s: "
                                        "std_srvs/srv/Trigger}}}"),
    "topic_entries_are_used": (f"nodes: {{a: {{run: json:dumps, target: main, publish: {{/x: {STRING}}}}}}}\n"
                               "topics: {/unused: {depth: 3}}"),
    "qos_compatible": ("nodes: {a: {run: json:dumps, target: main, publish: {/x: {type: std_msgs/msg/String, "
                       "reliability: best_effort}}},\n"
                       f"        b: {{run: json:dumps, target: main, subscribe: {{/x: {STRING}}}}}}}"),
    "hardware_topics": f"nodes: {{a: {{run: json:dumps, target: f, publish: {{/x: {STRING}}}}}}}",
    "chains_name_topics": (f"nodes: {{a: {{run: json:dumps, target: main, publish: {{/x: {STRING}}}}}}}\n"
                           "chains: {c: {first: /x, last: /y}}"),
    "timing_parameters_are_numbers": (f"python_path: [{CASES}]\nnodes: {{a: {{run: timing_module:main, "
                                      "target: main, parameters: {hz: fast}}}"),
    "shm_within_budget": (f"nodes: {{a: {{run: json:dumps, target: p, publish: {{/x: {STRING}}}}},\n"
                          f"        b: {{run: json:dumps, target: main, subscribe: {{/x: {STRING}}}}}}}\n"
                          "topics: {/x: {depth: 20000}}"),
}


def _reports(folder: Path, body: str, name: str) -> list[str]:
    """What rule ``name`` reports on the project ``body``, run after the rules before it (as check runs them)."""
    text = "name: rules\n" + body if body.startswith("targets") else HEAD + body
    path = folder / "project.yaml"
    path.write_text(textwrap.dedent(text))
    project = load_project(path)
    types = registry()
    report = CheckReport()
    load_messages(project, types, report)
    context = CheckContext(project, types, report, speaks_ros1=ros1_nodes(project), external=bridged(project))
    for rule in RULES:
        errors, warnings = len(report.errors), len(report.warnings)
        rule(context)
        if rule.__name__ == name:
            return report.errors[errors:] + report.warnings[warnings:]
    raise AssertionError(f"no rule {name}")


@pytest.mark.parametrize("name", sorted(BROKEN))
def test_each_rule_reports_what_breaks_it(tmp_path: Path, name: str) -> None:
    found = _reports(tmp_path, BROKEN[name], name)
    assert found, f"{name} reported nothing"
    assert all("project.yaml:" in line for line in found), found


def test_every_rule_is_shown_or_wraps_a_tested_check() -> None:
    wrappers = {"hosts_and_env", "actions_pair", "ros1_nodes_fit", "sources_exist", "bridged_endpoints_fit"}
    assert {rule.__name__ for rule in RULES} == set(BROKEN) | wrappers


@pytest.mark.parametrize(("publisher", "subscriber", "expected"), [
    ("a", "b", "inproc"), ("a", "c", "shm"), ("a", "d", "dds"), ("h1", "h2", "hw"), ("h1", "h3", None),
    ("h1", "a", None), ("g", "g", None), ("g", "a", "inproc"), (ROS1_BRIDGE, "g", None), (ROS1_BRIDGE, "a", "inproc"),
])
def test_one_edge_takes_one_transport(publisher: str, subscriber: str, expected: str | None) -> None:
    placement = Placement(
        process_of={"a": "p1", "b": "p1", "c": "p2", "d": "p3", "g": "p1", ROS1_BRIDGE: "p1"},
        host_of={"a": "x", "b": "x", "c": "x", "d": "y", "g": "x", ROS1_BRIDGE: "x"},
        fpga_of={"h1": "f1", "h2": "f1", "h3": "f2"}, gateways={"g": "f1"}, received_from_ros1={("g", "/t")})
    assert edge_transport("/t", publisher, subscriber, placement) == expected


@pytest.mark.parametrize("role", sorted(SYSTEM_NODES))
def test_every_system_node_resolves(role: str) -> None:
    module, _, function = SYSTEM_NODES[role].partition(":")
    assert callable(getattr(importlib.import_module(module), function))
