"""rclpy.action: ``ActionServer`` and ``ActionClient`` with rclpy's callbacks and futures, on hetros's
actions (three services and two topics, on whatever transport the plan chose)."""

from .client import ActionClient, ClientGoalHandle
from .server import ActionServer, CancelResponse, GoalResponse, ServerGoalHandle

__all__ = ["ActionClient", "ActionServer", "CancelResponse", "ClientGoalHandle", "GoalResponse", "ServerGoalHandle"]
