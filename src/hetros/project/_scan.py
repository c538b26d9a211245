"""Static scan of node sources for ``create_*`` calls (ROS-lite's map generator).

Used by ``hetros init`` to write a template project file and by ``hetros
check`` to find endpoints a node creates that the project does not declare.
Nothing is imported or run: the scan reads the syntax tree only.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass, field
from pathlib import Path

from .._errors import ProjectError
from .._files import parse_python

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
    # (section, endpoint) -> the line of the create_* call
    lines: dict[tuple[str, str], int] = field(default_factory=dict)
    # create_* calls whose endpoint name the scan cannot know (computed at run time), as messages
    unresolved: list[str] = field(default_factory=list)


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


_MAX_DEPTH = 4  # helper calls followed from a node function (a helper calling a helper, ...)


def _required_parameters(func: ast.FunctionDef) -> int:
    args = func.args
    return len(args.posonlyargs) + len(args.args) - len(args.defaults)


def _value(expr: ast.expr, bound: dict[str, str]) -> str | None:
    """A string the scan can know without running anything: a constant, a parameter bound to
    one, or an f-string of those; None otherwise."""
    if isinstance(expr, ast.Constant) and isinstance(expr.value, str):
        return expr.value
    if isinstance(expr, ast.Name):
        return bound.get(expr.id)
    if isinstance(expr, ast.JoinedStr):
        parts = []
        for part in expr.values:
            if isinstance(part, ast.FormattedValue):
                if part.format_spec is not None or part.conversion != -1:
                    return None
                value = _value(part.value, bound)
            else:
                value = _value(part, bound)
            if value is None:
                return None
            parts.append(value)
        return "".join(parts)
    return None


def _bind(func: ast.FunctionDef, call: ast.Call, bound: dict[str, str]) -> dict[str, str]:
    """What a helper's string parameters are at this call (what the scan can know of them)."""
    params = [a.arg for a in (*func.args.posonlyargs, *func.args.args)]
    values: dict[str, str] = {}
    defaults = func.args.defaults
    for name, default in zip(params[len(params) - len(defaults):], defaults, strict=True):
        if (known := _value(default, {})) is not None:
            values[name] = known
    for name, arg in zip(params, call.args, strict=False):
        if (known := _value(arg, bound)) is not None:
            values[name] = known
        else:
            values.pop(name, None)
    for keyword in call.keywords:
        if keyword.arg is not None:
            if (known := _value(keyword.value, bound)) is not None:
                values[keyword.arg] = known
            else:
                values.pop(keyword.arg, None)
    return values


class _Scanner:
    def __init__(self, tree: ast.Module, path: Path) -> None:
        self.imports = _import_map(tree)
        self.functions = {stmt.name: stmt for stmt in tree.body if isinstance(stmt, ast.FunctionDef)}
        self.path = path

    def collect(self, body: ast.AST, bound: dict[str, str], scanned: ScannedNode, depth: int) -> None:
        for call in ast.walk(body):
            if not isinstance(call, ast.Call):
                continue
            if isinstance(call.func, ast.Attribute) and call.func.attr in _KINDS and len(call.args) >= 2:
                kind = _KINDS[call.func.attr]
                name = _value(call.args[1], bound)
                if name is None:
                    scanned.unresolved.append(
                        f"{self.path.name}:{call.lineno}: {call.func.attr}(..., {ast.unparse(call.args[1])}) names "
                        f"its {kind} endpoint at run time; add it to nodes.{scanned.name}.{kind} by hand")
                    continue
                scanned.endpoints[kind][name] = _type_of(call.args[0], self.imports)
                scanned.lines[(kind, name)] = call.lineno
            elif isinstance(call.func, ast.Name) and call.func.id in self.functions and depth < _MAX_DEPTH:
                helper = self.functions[call.func.id]
                if helper is not body:
                    self.collect(helper, _bind(helper, call, bound), scanned, depth + 1)


def scan_file(path: Path, module: str) -> list[ScannedNode]:
    """Every node of a module: a top-level function taking just the node, or a class, whose body
    (or a helper it calls in the same module, its string arguments followed) creates endpoints.

    A function that needs more than the node (``stage(node, source, target)``) is a helper,
    never a node. An endpoint whose name only exists at run time is listed in ``unresolved``.
    """
    tree = parse_python(path, "node source", error=ProjectError)
    scanner = _Scanner(tree, path)
    found: list[ScannedNode] = []
    for stmt in tree.body:
        if isinstance(stmt, ast.FunctionDef) and _required_parameters(stmt) != 1:
            continue
        if not isinstance(stmt, ast.FunctionDef | ast.ClassDef):
            continue
        scanned = ScannedNode(stmt.name, f"{module}:{stmt.name}", str(path), stmt.lineno)
        scanner.collect(stmt, {}, scanned, 0)
        if any(scanned.endpoints.values()) or scanned.unresolved:
            found.append(scanned)
    return found


def module_name_for(path: Path, root: Path) -> str:
    """The module name of the source file ``path`` under ``root`` (``pkg/nodes.py``: ``pkg.nodes``)."""
    try:
        relative = path.resolve().relative_to(root.resolve())
    except ValueError:
        raise ProjectError(f"{path} is not inside {root}: name the folder the nodes' modules are imported from "
                           "with --root") from None
    if not relative.parts or (not relative.name.endswith(".py") and relative.suffix):
        raise ProjectError(f"{path} is not a Python source file under {root}; name the node's .py file")
    return ".".join(relative.with_suffix("").parts)
