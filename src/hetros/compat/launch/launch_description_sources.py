"""launch.launch_description_sources: where an included description comes from."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ._core import LaunchContext, LaunchFileError, normalize_to_list_of_substitutions, perform_substitutions


class LaunchDescriptionSource:
    """A launch file named by substitutions; its kind is told by its name unless the class fixes it."""

    python: bool | None = None

    def __init__(self, launch_file_path: Any) -> None:
        self.location_subs = normalize_to_list_of_substitutions(launch_file_path)

    def location(self, context: LaunchContext) -> str:
        return perform_substitutions(context, self.location_subs)

    def is_python(self, path: Path) -> bool:
        if self.python is not None:
            return self.python
        return path.suffix == ".py"


class PythonLaunchDescriptionSource(LaunchDescriptionSource):
    python = True


class FrontendLaunchDescriptionSource(LaunchDescriptionSource):
    python = False


class AnyLaunchDescriptionSource(LaunchDescriptionSource):
    pass


XMLLaunchDescriptionSource = FrontendLaunchDescriptionSource
YAMLLaunchDescriptionSource = FrontendLaunchDescriptionSource


def as_source(value: Any) -> LaunchDescriptionSource:
    """What IncludeLaunchDescription takes: a source, or (as newer launch allows) a path."""
    if isinstance(value, LaunchDescriptionSource):
        return value
    from ._core import LaunchDescription

    if isinstance(value, LaunchDescription):
        raise LaunchFileError("IncludeLaunchDescription of a LaunchDescription object: include its file instead, or "
                          "put its actions in a GroupAction")
    return AnyLaunchDescriptionSource(value)


__all__ = [
    "AnyLaunchDescriptionSource",
    "FrontendLaunchDescriptionSource",
    "LaunchDescriptionSource",
    "PythonLaunchDescriptionSource",
    "XMLLaunchDescriptionSource",
    "YAMLLaunchDescriptionSource",
]
