"""rclpy.subscription: the Subscription class (for type annotations and isinstance), as ``Node`` creates it."""

from .node import Subscription

__all__ = ["Subscription"]
