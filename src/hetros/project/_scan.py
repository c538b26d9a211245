"""Static scan of node sources for ``create_*`` calls (ROS-lite's map generator).

Used by ``hetros init`` to write a template project file and by ``hetros
check`` to find endpoints a node creates that the project does not declare.
Nothing is imported or run: the scan reads the syntax tree only.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from pathlib import Path

_KINDS = {
    "create_publisher": "publish",
    "create_subscription": "subscribe",
    "create_service": "services",
    "create_client": "clients",
    "create_action_server": "actions",
    "create_action_client": "action_clients",
}


@dataclass
class ScannedNode:
    name: str
    run: str
    source: str
    line: int
    endpoints: dict[str, dict[str, str]] = field(
        default_factory=lambda: {kind: {} for kind in _KINDS.values()}
    )


def _import_map(tree: ast.Module) -> dict[str, str]:
    """Local name -> 'pkg/kind/Type' for ``from hetros.interfaces.pkg.kind import Type``."""
    names: dict[str, str] = {}
    for stmt in ast.walk(tree):
        if isinstance(stmt, ast.ImportFrom) and stmt.module and stmt.module.startswith("hetros.interfaces."):
            parts = stmt.module.split(".")[2:]
            if len(parts) == 2:
                for alias in stmt.names:
                    names[alias.asname or alias.name] = f"{parts[0]}/{parts[1]}/{alias.name}"
    return names


def _type_of(node: ast.expr, imports: dict[str, str]) -> str:
    if isinstance(node, ast.Name):
        return imports.get(node.id, node.id)
    if isinstance(node, ast.Attribute):
        base = _type_of(node.value, imports)
        return f"{base}/{node.attr}" if "/" not in base else base
    return "?"


def scan_file(path: Path, module: str) -> list[ScannedNode]:
    """Every top-level function or class whose body calls ``create_*``."""
    source = path.read_text(encoding="utf-8")
    tree = ast.parse(source, filename=str(path))
    imports = _import_map(tree)
    found: list[ScannedNode] = []
    for stmt in tree.body:
        if not isinstance(stmt, (ast.FunctionDef, ast.ClassDef)):
            continue
        scanned = ScannedNode(stmt.name, f"{module}:{stmt.name}", str(path), stmt.lineno)
        for call in ast.walk(stmt):
            if not (isinstance(call, ast.Call) and isinstance(call.func, ast.Attribute)):
                continue
            kind = _KINDS.get(call.func.attr)
            if kind is None or len(call.args) < 2:
                continue
            name_arg = call.args[1]
            if not (isinstance(name_arg, ast.Constant) and isinstance(name_arg.value, str)):
                continue
            typename = _type_of(call.args[0], imports)
            scanned.endpoints[kind][name_arg.value] = typename
        if any(scanned.endpoints.values()):
            found.append(scanned)
    return found


def module_name_for(path: Path, root: Path) -> str:
    relative = path.resolve().relative_to(root.resolve()).with_suffix("")
    return ".".join(relative.parts)
