"""ROS 2's ``launch_ros``, as hetros serves it to Python launch files: ROS nodes, managed nodes,
components, and the namespace, remaps and parameters they start under (see :mod:`hetros.compat.launch`)."""

from . import actions, descriptions, event_handlers, events, parameter_descriptions, substitutions

__all__ = ["actions", "descriptions", "event_handlers", "events", "parameter_descriptions", "substitutions"]
