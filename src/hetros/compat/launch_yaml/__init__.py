"""launch_yaml, as hetros serves it to Python launch files: the source that includes a YAML launch file."""

from . import launch_description_sources

__all__ = ["launch_description_sources"]
