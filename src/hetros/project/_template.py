"""``hetros init``: a template project from the node sources' ``create_*`` calls."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ._scan import module_name_for, scan_file


def template_from_sources(files: list[Path], root: Path, name: str,
                          base: Path | None = None) -> tuple[dict[str, Any], list[str]]:
    """The template project, and what the scan could not follow (each naming file:line and the fix).
    Modules are named from ``root``; a project file written to another folder, ``base``, finds them
    through ``python_path:``."""
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
    project: dict[str, Any] = {"name": name, "targets": {"main": {"kind": "thread"}}, "nodes": nodes}
    if base is not None and (relative := os.path.relpath(root.resolve(), base.resolve())) != ".":
        project = {"name": name, "python_path": [relative], **project}
    return project, unresolved
