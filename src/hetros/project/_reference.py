"""The project file's reference (docs/PROJECT_FILE.md), generated from the model itself.

Every key, its kind, its default and what it does come from the pydantic classes of
``_model`` and the ``QoS`` dataclass, so the reference cannot drift from what ``hetros check``
accepts; a test compares the committed file with this output. Regenerate with
``hetros reference > docs/PROJECT_FILE.md``.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from typing import Any, Literal

from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined
from typing_extensions import Doc

from .._qos import QoS
from ._model import ActionSpec, EndpointSpec, ExternalSpec, HostSpec, NodeSpec, Project, Ros1Spec, Ros2Spec, TargetSpec

# each section: (heading, where it sits in the file, the class)
_SECTIONS: list[tuple[str, str, type[Any]]] = [
    ("The project", "the top level", Project),
    ("targets.<name>", "one target: where nodes run", TargetSpec),
    ("nodes.<name>", "one node", NodeSpec),
    ("nodes.<name>.publish/subscribe.<topic> (the mapping form)", "one endpoint with its own QoS", EndpointSpec),
    ("nodes.<name>.actions.<action> (the mapping form)", "one action server", ActionSpec),
    ("topics.<topic>", "one topic's QoS, the same on every transport", QoS),
    ("hosts.<name>", "one machine of the graph", HostSpec),
    ("external", "the ROS 1 and ROS 2 graphs this one joins", ExternalSpec),
    ("external.ros2", "the ROS 2 graph this one joins", Ros2Spec),
    ("external.ros1", "the ROS 1 graph this one joins", Ros1Spec),
]
_NAMED = {cls: heading for heading, _where, cls in _SECTIONS}


def _kind(annotation: Any) -> str:
    """A type as a project file's author reads it."""
    origin = typing.get_origin(annotation)
    args = typing.get_args(annotation)
    if origin is typing.Annotated:
        return _kind(args[0])
    if origin is Literal:
        return " or ".join(f"`{a}`" for a in args)
    if origin in (typing.Union, types.UnionType):
        shown = [_kind(a) for a in args if a is not type(None)]
        return " or ".join(dict.fromkeys(shown))
    if origin is dict:
        return f"mapping of name to {_kind(args[1])}"
    if origin is list:
        return f"list of {_kind(args[0])}"
    if annotation in _NAMED:
        return f"mapping (see {_NAMED[annotation]})"
    return {str: "text", int: "integer", float: "number", bool: "`true` or `false`"}.get(annotation, "any value")


def _bounds(metadata: list[Any]) -> str:
    """The constraints pydantic and annotated_types carry, as ">= 1, <= 1,000,000"."""
    words = {"ge": ">=", "gt": ">", "le": "<=", "lt": "<", "multiple_of": "a multiple of"}
    parts = []
    for item in metadata:
        for attr, word in words.items():
            value = getattr(item, attr, None)
            if isinstance(value, int | float) and not isinstance(value, bool):
                parts.append(f"{word} {value:,}" if isinstance(value, int) else f"{word} {value:g}")
    return ", ".join(dict.fromkeys(parts))


def _default(value: Any, factory: Any = None) -> str:
    if factory is not None:
        value = factory()
        if isinstance(value, dict) and value and all(isinstance(v, BaseModel) for v in value.values()):
            return ", ".join(f"`{k}`: {v.model_dump(exclude_defaults=True)}" for k, v in value.items())
    if value is PydanticUndefined or value is dataclasses.MISSING:
        return "required"
    if value is None or value == [] or value == {}:
        return "absent"
    return f"`{str(value).lower() if isinstance(value, bool) else value}`"


def _rows(cls: type[Any]) -> list[tuple[str, str, str, str]]:
    """``(key, kind, default, meaning)`` of every field of ``cls``."""
    rows = []
    if isinstance(cls, type) and issubclass(cls, BaseModel):
        for name, info in cls.model_fields.items():
            key = info.alias or name
            meaning = info.description or ""
            bounds = _bounds(info.metadata)
            rows.append((key, _kind(info.annotation) + (f" ({bounds})" if bounds else ""),
                         _default(info.default, info.default_factory), meaning))
        return rows
    hints = typing.get_type_hints(cls, include_extras=True)
    for field in dataclasses.fields(cls):
        annotation = hints[field.name]
        inner = [a for a in typing.get_args(annotation) if typing.get_origin(a) is typing.Annotated]
        extras = list(typing.get_args(annotation)[1:]) if typing.get_origin(annotation) is typing.Annotated else []
        for each in inner:
            extras += list(typing.get_args(each)[1:])
        meaning = next((e.documentation for e in extras if isinstance(e, Doc)), "")
        bounds = _bounds([e for e in extras if not isinstance(e, Doc | FieldInfo)])
        rows.append((field.name, _kind(annotation) + (f" ({bounds})" if bounds else ""), _default(field.default),
                     meaning))
    return rows


def reference_markdown() -> str:
    lines = [
        "<!-- DO NOT EDIT: generated by `hetros reference` from the project file's model "
        "(src/hetros/project/_model.py, src/hetros/_qos.py). -->",
        "# The project file",
        "",
        "One YAML document: the nodes, where each runs, what each publishes, subscribes, serves and",
        "calls, and the QoS of each topic. `hetros check` validates it against exactly what is listed",
        "here; an unknown key is an error naming the nearest known one. \"absent\" means the key may be",
        "left out. Names of topics and services follow ROS 2's rules; names of the project, targets",
        "and hosts are an ASCII letter, then letters, digits, `_` or `-` (at most 63).",
        "",
    ]
    for heading, where, cls in _SECTIONS:
        title = heading if cls is Project else f"`{heading}`"
        lines += [f"## {title}", "", where[0].upper() + where[1:] + ".", "",
                  "| key | kind | default | meaning |", "|---|---|---|---|"]
        lines += [f"| `{key}` | {kind} | {default} | {meaning} |" for key, kind, default, meaning in _rows(cls)]
        lines.append("")
    return "\n".join(lines)


def known_keys(location: tuple[str, ...]) -> list[str]:
    """The keys a mapping at ``location`` (a YAML path) may hold, for "did you mean"."""
    cls: Any = Project
    path = list(location)
    while path:
        step = path.pop(0)
        fields = _fields(cls)
        if step in fields:
            annotation = fields[step]
            target = _model_in(annotation)
            if target is None:
                return []
            if typing.get_origin(_unwrap(annotation)) is dict and path:
                path.pop(0)  # the name a mapping of names holds
            cls = target
        else:
            return []
    return sorted(_fields(cls))


def _fields(cls: Any) -> dict[str, Any]:
    if isinstance(cls, type) and issubclass(cls, BaseModel):
        return {info.alias or name: info.annotation for name, info in cls.model_fields.items()}
    if dataclasses.is_dataclass(cls):
        return {field.name: field.type for field in dataclasses.fields(cls)}
    return {}


def _unwrap(annotation: Any) -> Any:
    while typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    return annotation


def _model_in(annotation: Any) -> Any:
    """The model class a field leads to (through dicts, lists, unions), or None for a plain value."""
    annotation = _unwrap(annotation)
    if isinstance(annotation, type) and (issubclass(annotation, BaseModel) or dataclasses.is_dataclass(annotation)):
        return annotation
    for arg in typing.get_args(annotation):
        found = _model_in(arg)
        if found is not None:
            return found
    return None
