"""The packages a launch file's substitutions find: name -> source folder, filled by the evaluator from
the folders it is given (hetros runs packages from their sources: a package's share folder is its
source folder, where its launch/ and config/ files are)."""

from __future__ import annotations

from pathlib import Path

from ..launch import LaunchFileError

known: dict[str, Path] = {}


def package_folder(name: str, where: str) -> Path:
    if name not in known:
        raise LaunchFileError(f"{where}: package {name!r} not found (known: {', '.join(sorted(known)) or 'none'}); "
                          "pass its folder's parent with --package-path")
    return known[name]
