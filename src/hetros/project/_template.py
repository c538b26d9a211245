"""``hetros init``: a template project from the node sources' ``create_*`` calls."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._scan import module_name_for, scan_file


def template_from_sources(files: list[Path], root: Path, name: str) -> tuple[dict[str, Any], list[str]]:
    """The template project, and what the scan could not follow (each naming file:line and the fix)."""
    nodes: dict[str, Any] = {}
    unresolved: list[str] = []
    for path in files:
        for scanned in scan_file(path, module_name_for(path, root)):
            unresolved += scanned.unresolved
            entry: dict[str, Any] = {"run": scanned.run, "target": "main"}
            for section, endpoints in scanned.endpoints.items():
                if endpoints:
                    entry[section] = dict(endpoints)
            nodes[scanned.name] = entry
    return {"name": name, "targets": {"main": {"kind": "thread"}}, "nodes": nodes}, unresolved
