"""The names each package exports, pinned: a change to them is a decision, made here and in the changelog.

``hetros`` itself (the node API, QoS, the error tree), ``hetros.hw.nodes`` (the reference hardware
nodes) and the ROS shims (``rclpy``, ``rospy``) are the stable surface users write against. The other
packages' ``__all__`` are the architecture's seams: what one layer shares with another, free to change
with the code, but never silently (docs/ARCHITECTURE.md, "Public names").
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import pytest

PINNED = json.loads((Path(__file__).resolve().parents[1] / "data" / "public_names.json").read_text())
STABLE = {"hetros", "hetros.hw.nodes", "hetros.compat.rclpy", "hetros.compat.rospy"}


@pytest.mark.parametrize("package", sorted(PINNED))
def test_the_exported_names_are_the_pinned_ones(package: str) -> None:
    module = importlib.import_module(package)
    exported = sorted(module.__all__)
    assert exported == PINNED[package], (
        f"{package}.__all__ changed: added {sorted(set(exported) - set(PINNED[package]))}, removed "
        f"{sorted(set(PINNED[package]) - set(exported))}; if meant, update tests/data/public_names.json"
        + (" and say so in CHANGELOG.md (a stable surface)" if package in STABLE else ""))
    for name in exported:
        assert getattr(module, name) is not None, f"{package}.{name} is exported but does not resolve"
