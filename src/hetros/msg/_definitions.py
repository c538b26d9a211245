"""Reading .msg, .srv and .action files into rosbags field definitions.

rosbags parses leniently (it skips tokens it does not understand), so every
line is checked here first: a malformed definition is reported with its
file:line and the reason, instead of turning into a silently different type.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

# rosbags' own field-definition tuples are loosely typed; Any keeps them opaque here.
from typing import Any

from rosbags.interfaces import Nodetype
from rosbags.typesys import TypesysError, get_types_from_msg

from .._errors import DefinitionError

Typesdict = dict[str, Any]

_PRIMITIVES = frozenset(
    "bool byte char int8 uint8 int16 uint16 int32 uint32 int64 uint64 float32 float64 "
    "string wstring time duration".split()
)
_TYPE_RE = re.compile(
    r"^(?P<base>[A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*){0,2})"
    r"(?P<bound><=\d+)?(?P<array>\[(?:<=)?\d*\])?$"
)
_NAME_RE = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_PKG_RE = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class FieldUse:
    """Where a definition names a type, so an unknown type can be reported at its line."""

    typename: str
    path: str
    line: int


@dataclass(frozen=True)
class ParsedDefinition:
    """One message type: rosbags field definitions plus the lines that named types."""

    name: str
    text: str
    typedefs: Typesdict
    uses: tuple[FieldUse, ...]


def _strip_comment(line: str) -> str:
    if "=" in line.split("#", 1)[0] and line.split()[0].startswith("string"):
        return line.strip()
    return line.split("#", 1)[0].strip()


def lint_lines(lines: list[str], path: str, first_line: int, package: str) -> list[FieldUse]:
    """Check each line of one definition section; return the non-primitive types it names."""
    uses: list[FieldUse] = []
    seen: dict[str, int] = {}
    for offset, raw in enumerate(lines):
        lineno = first_line + offset
        line = _strip_comment(raw)
        if not line:
            continue
        parts = line.split(None, 1)
        if len(parts) < 2:
            raise DefinitionError(
                path, lineno, f"expected '<type> <name>', got {line!r} (a field needs a type and a name)"
            )
        typetok, rest = parts
        match = _TYPE_RE.match(typetok)
        if not match:
            raise DefinitionError(path, lineno, f"{typetok!r} is not a valid field type")
        if "=" in rest:
            name = rest.split("=", 1)[0].strip()
            value = rest.split("=", 1)[1].strip()
            if match.group("array"):
                raise DefinitionError(path, lineno, f"constant {name!r} cannot be an array")
            if not value:
                raise DefinitionError(path, lineno, f"constant {name!r} has no value after '='")
        else:
            name_and_default = rest.split(None, 1)
            name = name_and_default[0]
        if not _NAME_RE.match(name):
            raise DefinitionError(
                path, lineno, f"{name!r} is not a valid field name (letters, digits, '_'; starts with a letter)"
            )
        if name in seen:
            raise DefinitionError(path, lineno, f"field {name!r} is already defined on line {seen[name]}")
        seen[name] = lineno
        base = match.group("base")
        if match.group("bound") and base not in {"string", "wstring"}:
            raise DefinitionError(path, lineno, f"only strings take a '<=N' bound, not {base!r}")
        if base not in _PRIMITIVES:
            uses.append(FieldUse(qualify(base, package), path, lineno))
    return uses


def qualify(typename: str, package: str, kind: str = "msg") -> str:
    """Turn a type as written in a definition into the full ``pkg/msg/Name`` form."""
    if typename == "Header":
        return "std_msgs/msg/Header"
    parts = typename.split("/")
    if len(parts) == 1:
        return f"{package}/{kind}/{parts[0]}"
    if len(parts) == 2:
        return f"{parts[0]}/msg/{parts[1]}"
    return typename


def parse_section(lines: list[str], name: str, path: str, first_line: int) -> ParsedDefinition:
    """Parse one message section (a whole .msg, or one part of a .srv/.action)."""
    package = name.split("/", 1)[0]
    uses = lint_lines(lines, path, first_line, package)
    text = "\n".join(lines)
    # rosbags resolves relative names against a msg/ type, so parse as one and rename.
    parse_name = f"{package}/msg/{name.rsplit('/', 1)[-1]}"
    try:
        (consts, fields), = get_types_from_msg(text, parse_name).values()
    except TypesysError as exc:
        raise DefinitionError(path, first_line, f"cannot parse the definition of {name}: {exc}") from exc
    if not fields:
        fields = [("structure_needs_at_least_one_member", (Nodetype.BASE, ("uint8", 0)))]
    return ParsedDefinition(name, text, {name: (consts, fields)}, tuple(uses))


def split_sections(text: str, path: str, count: int) -> list[tuple[int, list[str]]]:
    """Split a .srv (2 parts) or .action (3 parts) on '---' lines; keep the start line of each."""
    sections: list[tuple[int, list[str]]] = [(1, [])]
    for lineno, line in enumerate(text.splitlines(), start=1):
        if line.strip() == "---":
            sections.append((lineno + 1, []))
        else:
            sections[-1][1].append(line)
    if len(sections) != count:
        kind = "a .srv file" if count == 2 else "an .action file"
        raise DefinitionError(
            path,
            len(text.splitlines()) or 1,
            f"{kind} needs exactly {count - 1} '---' separator line(s), found {len(sections) - 1}",
        )
    return sections


def action_derived_typedefs(base: str) -> Typesdict:
    """The types ROS 2 derives from an action: its two services and its feedback topic."""
    uuid = (Nodetype.NAME, "unique_identifier_msgs/msg/UUID")
    return {
        f"{base}_SendGoal_Request": ([], [("goal_id", uuid), ("goal", (Nodetype.NAME, f"{base}_Goal"))]),
        f"{base}_SendGoal_Response": (
            [],
            [("accepted", (Nodetype.BASE, ("bool", 0))), ("stamp", (Nodetype.NAME, "builtin_interfaces/msg/Time"))],
        ),
        f"{base}_GetResult_Request": ([], [("goal_id", uuid)]),
        f"{base}_GetResult_Response": (
            [],
            [("status", (Nodetype.BASE, ("int8", 0))), ("result", (Nodetype.NAME, f"{base}_Result"))],
        ),
        f"{base}_FeedbackMessage": ([], [("goal_id", uuid), ("feedback", (Nodetype.NAME, f"{base}_Feedback"))]),
    }


@dataclass(frozen=True)
class PackageDefinitions:
    """Everything one interface package folder defines."""

    package: str
    messages: tuple[ParsedDefinition, ...]
    services: tuple[str, ...]
    actions: tuple[str, ...]


def read_package(folder: Path) -> PackageDefinitions:
    """Read ``<pkg>/msg/*.msg``, ``<pkg>/srv/*.srv`` and ``<pkg>/action/*.action``."""
    package = folder.name
    if not _PKG_RE.match(package):
        raise DefinitionError(
            str(folder), 0, f"package folder name must be lower_snake_case, not {package!r}"
        )
    parsed: list[ParsedDefinition] = []
    services: list[str] = []
    actions: list[str] = []
    for path in sorted((folder / "msg").glob("*.msg")):
        text = path.read_text(encoding="utf-8")
        parsed.append(parse_section(text.splitlines(), f"{package}/msg/{path.stem}", str(path), 1))
    for path in sorted((folder / "srv").glob("*.srv")):
        text = path.read_text(encoding="utf-8")
        (l1, request), (l2, response) = split_sections(text, str(path), 2)
        base = f"{package}/srv/{path.stem}"
        parsed.append(parse_section(request, f"{base}_Request", str(path), l1))
        parsed.append(parse_section(response, f"{base}_Response", str(path), l2))
        services.append(base)
    for path in sorted((folder / "action").glob("*.action")):
        text = path.read_text(encoding="utf-8")
        sections = split_sections(text, str(path), 3)
        base = f"{package}/action/{path.stem}"
        for suffix, (first, lines) in zip(("Goal", "Result", "Feedback"), sections, strict=True):
            parsed.append(parse_section(lines, f"{base}_{suffix}", str(path), first))
        derived = action_derived_typedefs(base)
        for name, typedef in derived.items():
            parsed.append(ParsedDefinition(name, "", {name: typedef}, ()))
        actions.append(base)
    if not parsed:
        raise DefinitionError(
            str(folder), 0, "no msg/*.msg, srv/*.srv or action/*.action files found in this package folder"
        )
    return PackageDefinitions(package, tuple(parsed), tuple(services), tuple(actions))


def find_packages(folder: Path) -> list[Path]:
    """A folder is a package (has msg/, srv/ or action/) or holds packages one level down."""
    if not folder.is_dir():
        raise DefinitionError(str(folder), 0, "message package folder does not exist")
    if any((folder / kind).is_dir() for kind in ("msg", "srv", "action")):
        return [folder]
    found = [
        child
        for child in sorted(folder.iterdir())
        if child.is_dir() and any((child / kind).is_dir() for kind in ("msg", "srv", "action"))
    ]
    if not found:
        raise DefinitionError(
            str(folder), 0, "holds no package: expected <pkg>/msg, <pkg>/srv or <pkg>/action folders"
        )
    return found
