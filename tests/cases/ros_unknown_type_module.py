"""A node module written for ROS 2 that imports an interface hetros does not know (a check case)."""
from lifecycle_msgs.srv import ChangeStates  # noqa: F401


def main() -> None:
    pass
