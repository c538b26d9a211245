"""ROS 2's ``launch``, as hetros serves it to Python launch files: a description's actions,
substitutions and conditions, evaluated as ``ros2 launch`` evaluates them, into the nodes they start
(:mod:`hetros.compat.launch_eval` runs a file; ``hetros import ros2launch`` and ``hetros launch``
turn what it records into a project)."""

from . import actions, conditions, event_handlers, events, launch_description_sources, substitutions
from ._core import (
    Action,
    Condition,
    LaunchContext,
    LaunchDescription,
    LaunchDescriptionEntity,
    LaunchFileError,
    SomeSubstitutionsType,
    SomeSubstitutionsType_types_tuple,
    Substitution,
)
from .events import Event

LaunchDescriptionSource = launch_description_sources.LaunchDescriptionSource

__all__ = [
    "Action",
    "Condition",
    "Event",
    "LaunchContext",
    "LaunchDescription",
    "LaunchDescriptionEntity",
    "LaunchDescriptionSource",
    "LaunchFileError",
    "SomeSubstitutionsType",
    "SomeSubstitutionsType_types_tuple",
    "Substitution",
    "actions",
    "conditions",
    "event_handlers",
    "events",
    "launch_description_sources",
    "substitutions",
]
