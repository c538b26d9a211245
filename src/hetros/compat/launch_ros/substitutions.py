"""launch_ros.substitutions: packages' folders and executables."""

from __future__ import annotations

from typing import Any

from ..launch import LaunchContext, Substitution
from ..launch.utilities import normalize_to_list_of_substitutions, perform_substitutions
from ._packages import package_folder


class FindPackagePrefix(Substitution):
    def __init__(self, package: Any) -> None:
        super().__init__()
        self.package = normalize_to_list_of_substitutions(package)

    def perform(self, context: LaunchContext) -> str:
        return str(package_folder(perform_substitutions(context, self.package), self.where))


class FindPackageShare(FindPackagePrefix):
    """A package's share folder: under hetros, its source folder."""

    def find(self, package_name: str) -> str:
        return str(package_folder(package_name, self.where))


class FindPackage(FindPackagePrefix):
    pass


class ExecutableInPackage(Substitution):
    """``package``'s ``executable``: an ExecuteProcess of it runs that node of the package."""

    def __init__(self, executable: Any, package: Any) -> None:
        super().__init__()
        self.executable = normalize_to_list_of_substitutions(executable)
        self.package = normalize_to_list_of_substitutions(package)

    def package_and_executable(self, context: LaunchContext) -> tuple[str, str]:
        return perform_substitutions(context, self.package), perform_substitutions(context, self.executable)

    def perform(self, context: LaunchContext) -> str:
        package, executable = self.package_and_executable(context)
        return str(package_folder(package, self.where) / "lib" / package / executable)


__all__ = ["ExecutableInPackage", "FindPackage", "FindPackagePrefix", "FindPackageShare"]
