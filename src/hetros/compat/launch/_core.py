"""The entities of a launch description, as ROS 2's ``launch`` defines them, evaluated the way its
``LaunchService`` visits them: a description is a tree of actions; visiting one (its condition first)
may give more entities to visit, in order; substitutions are performed against one context whose launch
configurations are scoped by groups and includes.

hetros does not start processes while visiting: a node action records what it would start
(:meth:`LaunchContext.record`), and ``hetros import``/``hetros launch`` turn the records into a project.
Every entity remembers the launch-file line that made it, so a refusal names it."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any

from ..._errors import LaunchFileError
from .._where import caller_place


class LaunchDescriptionEntity:
    """Anything a launch description holds: visiting it may give further entities."""

    def __init__(self) -> None:
        self.where = caller_place()

    def visit(self, context: LaunchContext) -> list[LaunchDescriptionEntity] | None:
        return None

    def describe(self) -> str:
        return type(self).__name__

    def get_sub_entities(self) -> list[LaunchDescriptionEntity]:
        return []


class Substitution:
    """A string known only when the launch runs: performed against the context."""

    def __init__(self) -> None:
        self.where = caller_place()

    def perform(self, context: LaunchContext) -> str:
        raise NotImplementedError

    def describe(self) -> str:
        return type(self).__name__

    def __add__(self, other: Any) -> list[Any]:
        return [self, other]

    def __radd__(self, other: Any) -> list[Any]:
        return [other, self]


SomeSubstitutionsType = str | Substitution | Iterable[str | Substitution]
SomeSubstitutionsType_types_tuple = (str, Substitution)


class TextSubstitution(Substitution):
    def __init__(self, *, text: str) -> None:
        super().__init__()
        self.text = text

    def perform(self, context: LaunchContext) -> str:
        return self.text

    def describe(self) -> str:
        return repr(self.text)


def normalize_to_list_of_substitutions(subs: Any) -> list[Substitution]:
    """As launch's utility: a string, a path, a substitution or an iterable of them, as substitutions."""
    if isinstance(subs, (str, os.PathLike)):
        return [TextSubstitution(text=os.fspath(subs))]
    if isinstance(subs, Substitution):
        return [subs]
    if isinstance(subs, (int, float, bool)):
        return [TextSubstitution(text=str(subs))]
    try:
        items = list(subs)
    except TypeError:
        raise LaunchFileError(f"a substitution must be a str, a Substitution or a list of them, not {subs!r}") from None
    return [item for sub in items for item in normalize_to_list_of_substitutions(sub)]


def perform_substitutions(context: LaunchContext, subs: Any) -> str:
    return "".join(sub.perform(context) for sub in normalize_to_list_of_substitutions(subs))


class Condition:
    """Whether an action is visited: ``evaluate`` against the context."""

    def __init__(self, *, predicate: Callable[[LaunchContext], bool] | None = None) -> None:
        self._predicate = predicate

    def evaluate(self, context: LaunchContext) -> bool:
        if self._predicate is None:
            raise NotImplementedError
        return self._predicate(context)

    def describe(self) -> str:
        return type(self).__name__


class Action(LaunchDescriptionEntity):
    """An action is visited when its condition holds; what ``execute`` returns is visited next."""

    def __init__(self, *, condition: Condition | None = None) -> None:
        super().__init__()
        self.condition = condition

    def visit(self, context: LaunchContext) -> list[LaunchDescriptionEntity] | None:
        if self.condition is not None and not self.condition.evaluate(context):
            return None
        return self.execute(context)

    def execute(self, context: LaunchContext) -> list[LaunchDescriptionEntity] | None:
        return None


class LaunchDescription(LaunchDescriptionEntity):
    def __init__(self, initial_entities: Iterable[LaunchDescriptionEntity] | None = None, *,
                 deprecated_reason: str | None = None) -> None:
        super().__init__()
        self.entities = list(initial_entities or [])
        self.deprecated_reason = deprecated_reason

    def add_entity(self, entity: LaunchDescriptionEntity) -> None:
        self.entities.append(entity)

    add_action = add_entity

    def visit(self, context: LaunchContext) -> list[LaunchDescriptionEntity] | None:
        return list(self.entities)

    def get_launch_arguments(self, conditional_inclusion: bool = False) -> list[Any]:
        from .actions import DeclareLaunchArgument

        return [e for e in self.entities if isinstance(e, DeclareLaunchArgument)]

    def get_sub_entities(self) -> list[LaunchDescriptionEntity]:
        return list(self.entities)


class LaunchContext:
    """What the actions and substitutions of one launch read and change: launch configurations (scoped
    by groups), the environment, the launch file being read; and, hetros's part, the records of what
    the launch would start."""

    def __init__(self, *, argv: list[str] | None = None, noninteractive: bool = True) -> None:
        self.launch_configurations: dict[str, Any] = {}
        self.environment: dict[str, str] = dict(os.environ)
        self.argv = list(argv or [])
        self.noninteractive = noninteractive
        self.is_shutdown = False
        self._configuration_stack: list[dict[str, Any]] = []
        self._environment_stack: list[dict[str, str]] = []
        self._files: list[Path] = []
        self.records: list[dict[str, Any]] = []
        self._locals: dict[str, Any] = {}
        self.pending: list[LaunchDescriptionEntity] = []  # what handlers registered in code give

    # -- scopes --------------------------------------------------------------------------

    def _push_launch_configurations(self) -> None:
        self._configuration_stack.append(dict(self.launch_configurations))

    def _pop_launch_configurations(self) -> None:
        self.launch_configurations = self._configuration_stack.pop()

    def _push_environment(self) -> None:
        self._environment_stack.append(dict(self.environment))

    def _pop_environment(self) -> None:
        self.environment = self._environment_stack.pop()

    def _reset_environment(self) -> None:
        self.environment = dict(os.environ)

    # -- the file being read -------------------------------------------------------------

    def entering(self, path: Path) -> None:
        self._files.append(path)

    def leaving(self) -> None:
        self._files.pop()

    @property
    def current_launch_file(self) -> Path:
        if not self._files:
            raise LaunchFileError("no launch file is being read")
        return self._files[-1]

    # -- launch's context API ------------------------------------------------------------

    def perform_substitution(self, substitution: Substitution) -> str:
        return substitution.perform(self)

    def extend_locals(self, extension: dict[str, Any]) -> None:
        self._locals.update(extension)

    def get_locals_as_dict(self) -> dict[str, Any]:
        return dict(self._locals)

    @property
    def locals(self) -> Any:
        class _Locals:
            def __getattr__(_self, name: str) -> Any:
                try:
                    return self._locals[name]
                except KeyError:
                    raise AttributeError(name) from None
        return _Locals()

    def emit_event_sync(self, event: Any) -> None:
        raise LaunchFileError("emitting events while a description is read has no counterpart in hetros")

    emit_event = emit_event_sync

    def register_event_handler(self, handler: Any, append: bool = False) -> None:
        from .actions import RegisterEventHandler

        self.pending.extend(RegisterEventHandler(handler).execute(self) or [])

    # -- hetros: what the launch starts ------------------------------------------------------

    def record(self, kind: str, where: str, **fields: Any) -> None:
        self.records.append({"kind": kind, "where": where, **fields})

    def note(self, where: str, text: str) -> None:
        self.record("note", where, text=text)


def visit_all(entity: LaunchDescriptionEntity, context: LaunchContext) -> None:
    """Visit ``entity`` and, depth first and in order, everything its visits give."""
    pending = [entity]
    while pending:
        current = pending.pop()
        if not isinstance(current, LaunchDescriptionEntity):
            raise LaunchFileError(f"a launch description holds actions, not {current!r}")
        found = [*(current.visit(context) or []), *context.pending]
        context.pending.clear()
        pending.extend(reversed(found))


__all__ = [
    "Action",
    "Condition",
    "LaunchContext",
    "LaunchDescription",
    "LaunchDescriptionEntity",
    "LaunchFileError",
    "SomeSubstitutionsType",
    "SomeSubstitutionsType_types_tuple",
    "Substitution",
    "TextSubstitution",
    "caller_place",
    "normalize_to_list_of_substitutions",
    "perform_substitutions",
    "visit_all",
]
