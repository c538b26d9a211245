"""rclpy.publisher: the Publisher class (for type annotations and isinstance), as ``Node`` creates it."""

from .node import Publisher

__all__ = ["Publisher"]
