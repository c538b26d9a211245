"""launch_ros.events: the lifecycle events a launch file emits."""

from ...launch.events import matches_action
from . import lifecycle

__all__ = ["lifecycle", "matches_action"]
