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

from .._errors import DefinitionError
from ._validate import INT_RANGES

Typesdict = dict[str, Any]

_PRIMITIVES = frozenset(
    "bool byte char int8 uint8 int16 uint16 int32 uint32 int64 uint64 float32 float64 "
    "string wstring time duration".split()
)
_TYPE_RE = re.compile(
    r"^(?P<base>[A-Za-z][A-Za-z0-9_]*(?:/[A-Za-z][A-Za-z0-9_]*){0,2})"
    r"(?P<bound><=\d+)?(?P<array>\[(?P<upper><=)?(?P<size>\d*)\])?$"
)
# rosidl's grammar (rosidl_adapter.parser): field names lower_snake_case without a double or
# trailing underscore, constants UPPER_CASE, types PascalCase, packages lower_snake_case.
_NAME_RE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")
_CONSTANT_RE = re.compile(r"^[A-Z]([A-Z0-9_]?[A-Z0-9]+)*$")
TYPE_NAME_RE = re.compile(r"^[A-Z][A-Za-z0-9]*$")
_PKG_RE = re.compile(r"^(?!.*__)(?!.*_$)[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class FieldUse:
    """Where a definition names a type, so an unknown type can be reported at its line."""

    typename: str
    path: str
    line: int
    field: str = ""


@dataclass(frozen=True)
class ParsedDefinition:
    """One message type: rosbags field definitions plus the lines that named types, and defaults."""

    name: str
    text: str
    typedefs: Typesdict
    uses: tuple[FieldUse, ...]
    defaults: tuple[tuple[str, Any], ...] = ()


def _strip_comment(line: str) -> str:
    code = line.split("#", 1)[0]
    head = code.split()
    if "=" in code and head and head[0].startswith(("string", "wstring")):
        return line.strip()  # a string constant keeps everything after '=', '#' included
    return code.strip()


def _scalar(base: str, text: str, what: str) -> Any:
    """The value of a constant or default of primitive type ``base``, checked like rosidl does."""
    text = text.strip()
    if base in INT_RANGES:
        try:
            value = int(text, 0) if text.lower().startswith(("0x", "0o", "0b")) else int(text)
        except ValueError:
            raise ValueError(f"{what} must be an integer for {base}, not {text!r}") from None
        low, high = INT_RANGES[base]
        if not low <= value <= high:
            raise ValueError(f"{what} {value} is out of range for {base} ({low}..{high})")
        return value
    if base in ("float32", "float64"):
        try:
            return float(text)
        except ValueError:
            raise ValueError(f"{what} must be a number for {base}, not {text!r}") from None
    if base == "bool":
        lowered = text.lower()
        if lowered in ("true", "1"):
            return True
        if lowered in ("false", "0"):
            return False
        raise ValueError(f"{what} must be true or false for bool, not {text!r}")
    if base in ("string", "wstring"):
        if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
            return text[1:-1]
        return text
    raise ValueError(f"{base} fields take no {what}")


def _split_array(text: str, what: str) -> list[str]:
    text = text.strip()
    if not (text.startswith("[") and text.endswith("]")):
        raise ValueError(f"{what} of an array must be written [a, b, ...], not {text!r}")
    inner = text[1:-1].strip()
    return [item.strip() for item in inner.split(",")] if inner else []


def _default(match: re.Match[str], text: str) -> Any:
    base = match.group("base")
    if base not in _PRIMITIVES or base in ("time", "duration"):
        raise ValueError(f"a field of type {base} takes no default value")
    if not match.group("array"):
        value = _scalar(base, text, "the default value")
        bound = match.group("bound")
        if bound and isinstance(value, str) and len(value) > int(bound[2:]):
            raise ValueError(f"the default value is longer than the bound {bound[2:]}")
        return value
    items = [_scalar(base, item, "an element of the default value") for item in _split_array(text, "the default")]
    size = match.group("size")
    if size and not match.group("upper") and len(items) != int(size):
        raise ValueError(f"the default value has {len(items)} elements; the array has exactly {size}")
    if size and match.group("upper") and len(items) > int(size):
        raise ValueError(f"the default value has {len(items)} elements; the array holds at most {size}")
    return items


def lint_lines(lines: list[str], path: str, first_line: int, package: str
               ) -> tuple[list[FieldUse], dict[str, Any]]:
    """Check each line of one definition section against rosidl's grammar.

    Returns the non-primitive types it names (with their lines) and the default values of
    its fields (ROS 2 honours them: ``int32 x 5`` makes 5 the default).
    """
    uses: list[FieldUse] = []
    defaults: dict[str, Any] = {}
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
        base = match.group("base")
        if base == "wstring":
            raise DefinitionError(path, lineno, "wstring is not supported in .msg files here (rosbags, which "
                                  "hetros builds types with, reads it as a message type); use string (UTF-8)")
        if match.group("bound") and base not in {"string", "wstring"}:
            raise DefinitionError(path, lineno, f"only strings take a '<=N' bound, not {base!r}")
        if match.group("upper") and not match.group("size"):
            raise DefinitionError(path, lineno, f"{typetok!r}: a bounded array needs its bound, like [<=10]")
        name_part = rest.split("=", 1)[0] if "=" in rest else rest
        tokens = name_part.split(None, 1)
        name = tokens[0] if tokens else ""
        if "=" in rest:
            if len(tokens) > 1:
                raise DefinitionError(path, lineno, f"unexpected {tokens[1]!r} after constant name {name!r}")
            value = rest.split("=", 1)[1].strip()
            if not _CONSTANT_RE.match(name):
                raise DefinitionError(path, lineno, f"{name!r} is not a valid constant name (UPPER_CASE letters, "
                                      "digits and single '_', starting with a letter)")
            if match.group("array"):
                raise DefinitionError(path, lineno, f"constant {name!r} cannot be an array")
            if not value:
                raise DefinitionError(path, lineno, f"constant {name!r} has no value after '='")
            if base not in _PRIMITIVES or base in ("time", "duration"):
                raise DefinitionError(path, lineno, f"constant {name!r} must have a primitive type, not {base!r}")
            try:
                _scalar(base, value, f"constant {name}")
            except ValueError as exc:
                raise DefinitionError(path, lineno, str(exc)) from None
        else:
            if not _NAME_RE.match(name):
                raise DefinitionError(
                    path, lineno,
                    f"{name!r} is not a valid field name (lower_snake_case: letters, digits and single '_', "
                    "starting with a letter, not ending with '_')",
                )
            if len(tokens) > 1:
                try:
                    defaults[name] = _default(match, tokens[1])
                except ValueError as exc:
                    raise DefinitionError(path, lineno, f"field {name!r}: {exc}") from None
        if name in seen:
            raise DefinitionError(path, lineno, f"field {name!r} is already defined on line {seen[name]}")
        seen[name] = lineno
        if base not in _PRIMITIVES:
            full = qualify(base, package)
            short = full.rsplit("/", 1)[-1]
            if not TYPE_NAME_RE.match(short):
                raise DefinitionError(path, lineno, f"{base!r} is not a valid type name (PascalCase, "
                                      "starting with an upper-case letter)")
            uses.append(FieldUse(full, path, lineno, name))
    return uses, defaults


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
    short = name.rsplit("/", 1)[-1]
    if not TYPE_NAME_RE.match(short.split("_", 1)[0] if "/srv/" in name or "/action/" in name else short):
        raise DefinitionError(path, 1, f"{short.split('_', 1)[0]!r} is not a valid type name: rename the file "
                              "to PascalCase (letters and digits, starting with an upper-case letter)")
    uses, defaults = lint_lines(lines, path, first_line, package)
    text = "\n".join(lines)
    # rosbags resolves relative names against a msg/ type, so parse as one and rename.
    parse_name = f"{package}/msg/{name.rsplit('/', 1)[-1]}"
    from rosbags.typesys import TypesysError, get_types_from_msg  # the parser: on first use only

    try:
        (consts, fields), = get_types_from_msg(text, parse_name).values()
    except TypesysError as exc:
        raise DefinitionError(path, first_line, f"cannot parse the definition of {name}: {exc}") from exc
    if not fields:
        fields = [("structure_needs_at_least_one_member", (Nodetype.BASE, ("uint8", 0)))]
    return ParsedDefinition(name, text, {name: (consts, fields)}, tuple(uses), tuple(defaults.items()))


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


def _read(path: Path) -> str:
    raw = path.read_bytes()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw.count(b"\n", 0, exc.start) + 1
        raise DefinitionError(str(path), line, f"not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset "
                              f"{exc.start}); save the file as UTF-8") from None
    if "\x00" in text:
        raise DefinitionError(str(path), text.count("\n", 0, text.index("\x00")) + 1,
                              "a NUL character; interface files are text")
    return text


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
        text = _read(path)
        parsed.append(parse_section(text.splitlines(), f"{package}/msg/{path.stem}", str(path), 1))
    for path in sorted((folder / "srv").glob("*.srv")):
        text = _read(path)
        (l1, request), (l2, response) = split_sections(text, str(path), 2)
        base = f"{package}/srv/{path.stem}"
        parsed.append(parse_section(request, f"{base}_Request", str(path), l1))
        parsed.append(parse_section(response, f"{base}_Response", str(path), l2))
        services.append(base)
    for path in sorted((folder / "action").glob("*.action")):
        text = _read(path)
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
