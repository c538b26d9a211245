"""The project file: one YAML document, validated by pydantic, errors with YAML paths."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from .._errors import ProjectError

RESERVED_TARGET = "launcher"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class TargetSpec(_Strict):
    kind: Literal["thread", "process", "fpga", "host"]
    cpus: list[int] = Field(default_factory=list)
    clock_mhz: float | None = None
    sim: str | None = None
    address: str | None = None

    @field_validator("cpus")
    @classmethod
    def _cpus(cls, value: list[int]) -> list[int]:
        for cpu in value:
            if cpu < 0:
                raise ValueError(f"cpu numbers must be >= 0, not {cpu!r}")
        return value


class EndpointSpec(_Strict):
    """An endpoint with its own QoS request, checked against its peers' (ROS 2 request/offer)."""

    type: str
    reliability: Literal["reliable", "best_effort"] | None = None
    durability: Literal["volatile", "transient_local"] | None = None


class NodeSpec(_Strict):
    run: str
    target: str
    publish: dict[str, str | EndpointSpec] = Field(default_factory=dict)
    subscribe: dict[str, str | EndpointSpec] = Field(default_factory=dict)
    services: dict[str, str] = Field(default_factory=dict)
    clients: dict[str, str] = Field(default_factory=dict)
    parameters: dict[str, Any] = Field(default_factory=dict)
    restart: Literal["never", "on-failure"] = "never"
    required: bool = False
    max_restarts: int = Field(default=3, ge=0)

    def types(self, section: str) -> dict[str, str]:
        """Endpoint name -> type name for publish/subscribe/services/clients."""
        table: dict[str, str | EndpointSpec] = getattr(self, section)
        return {k: (v if isinstance(v, str) else v.type) for k, v in table.items()}

    def endpoint(self, section: str, name: str) -> EndpointSpec | None:
        value = getattr(self, section).get(name)
        return value if isinstance(value, EndpointSpec) else None

    @field_validator("run")
    @classmethod
    def _run(cls, value: str) -> str:
        module, sep, attr = value.partition(":")
        if not sep or not module or not attr:
            raise ValueError(f"run must be 'module:function_or_class', not {value!r}")
        return value


class TopicSpec(_Strict):
    reliability: Literal["reliable", "best_effort"] = "reliable"
    history: Literal["keep_all", "keep_last"] = "keep_all"
    depth: int = Field(default=10, ge=1)
    durability: Literal["volatile", "transient_local"] = "volatile"
    publish_timeout: float = Field(default=5.0, gt=0)


class ExternalSpec(_Strict):
    ros2: dict[str, Any] | None = None
    ros1: dict[str, Any] | None = None


class Project(_Strict):
    name: str
    messages: list[str] = Field(default_factory=list)
    targets: dict[str, TargetSpec] = Field(default_factory=lambda: {"main": TargetSpec(kind="thread")})
    nodes: dict[str, NodeSpec]
    topics: dict[str, TopicSpec] = Field(default_factory=dict)
    external: ExternalSpec | None = None

    @field_validator("targets")
    @classmethod
    def _targets(cls, value: dict[str, TargetSpec]) -> dict[str, TargetSpec]:
        if RESERVED_TARGET in value:
            raise ValueError(f"{RESERVED_TARGET!r} is reserved for the launching process; pick another name")
        return value


class LoadedProject:
    """A validated project plus where it came from (for paths and line numbers)."""

    def __init__(self, model: Project, path: Path, lines: dict[tuple[str, ...], int]) -> None:
        self.model = model
        self.path = path
        self.root = path.parent
        self._lines = lines

    def where(self, *yaml_path: str | int) -> str:
        """``file:line: a.b.c`` for a YAML path (the line of the nearest known ancestor)."""
        key = tuple(str(p) for p in yaml_path)
        while key and key not in self._lines:
            key = key[:-1]
        line = self._lines.get(key)
        dotted = ".".join(str(p) for p in yaml_path)
        return f"{self.path}:{line}: {dotted}" if line else f"{self.path}: {dotted}"


def _line_index(node: yaml.Node, prefix: tuple[str, ...], out: dict[tuple[str, ...], int]) -> None:
    out[prefix] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        for key, value in node.value:
            child = (*prefix, str(key.value))
            out[child] = key.start_mark.line + 1
            _line_index(value, child, out)
            out[child] = key.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for index, item in enumerate(node.value):
            _line_index(item, (*prefix, str(index)), out)


def load_project(path: str | Path) -> LoadedProject:
    """Read and validate a project file; every error names file:line and the YAML path."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise ProjectError(f"cannot read project file {path}: {exc.strerror}") from exc
    try:
        tree = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        raise ProjectError(f"{where}: not valid YAML: {getattr(exc, 'problem', exc)}") from exc
    lines: dict[tuple[str, ...], int] = {}
    if tree is not None:
        _line_index(tree, (), lines)
    if not isinstance(data, dict):
        raise ProjectError(f"{path}: the project file must be a mapping with name, targets and nodes")
    try:
        model = Project.model_validate(data)
    except ValidationError as exc:
        loaded = LoadedProject(Project.model_construct(name="?", nodes={}), path, lines)
        problems = []
        for error in exc.errors():
            loc = [str(p) for p in error["loc"]]
            message = error["msg"]
            if error["type"] == "extra_forbidden":
                message = f"unknown key {loc[-1]!r}; check its spelling against the documented keys"
            elif error["type"] == "missing":
                message = f"required key {loc[-1]!r} is missing"
            elif error["type"] == "literal_error":
                message = f"{message}, not {error.get('input')!r}"
            problems.append(f"{loaded.where(*loc)}: {message}")
        raise ProjectError("invalid project file:\n" + "\n".join(f"  - {p}" for p in problems)) from None
    return LoadedProject(model, path, lines)
