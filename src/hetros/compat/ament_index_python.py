"""ament_index_python, as hetros serves it: a package's share folder without an install step.

ROS 2 finds ``share/<package>`` under the install prefix that colcon filled from the package's
``setup.py`` ``data_files``. hetros runs packages from their source folders, so a package is found by
its ``package.xml`` on the import path, and its share folder is laid out on first use: a folder of
links to the files ``data_files`` installs under ``share/<package>`` (for a package without a
``setup.py``, an ament_cmake one, its source folder stands in for it).
"""

from __future__ import annotations

import atexit
import os
import re
import shutil
import sys
import tempfile
import threading
from pathlib import Path

from .._errors import Error

_made: dict[str, Path] = {}
_lock = threading.Lock()
_folder: list[Path] = []


class PackageNotFoundError(KeyError, Error):
    """No folder on the import path holds a package.xml naming the package."""


def _package_folder(package_name: str) -> Path:
    for entry in sys.path:
        for candidate in (Path(entry or "."), Path(entry or ".") / package_name):
            xml = candidate / "package.xml"
            if xml.is_file():
                found = re.search(r"<name>\s*([\w-]+)\s*</name>", xml.read_text(encoding="utf-8"))
                if found and found.group(1) == package_name:
                    return candidate.resolve()
    raise PackageNotFoundError(f"package {package_name!r} not found: hetros looks for its package.xml in the "
                               "folders nodes are imported from (the project file's folder and python_path:)")


def _share_root() -> Path:
    if not _folder:
        folder = Path(tempfile.mkdtemp(prefix="hetros-share-", dir=os.environ.get("XDG_RUNTIME_DIR")))
        atexit.register(shutil.rmtree, folder, True)
        _folder.append(folder)
    return _folder[0]


def get_package_prefix(package_name: str) -> str:
    """The install prefix whose ``share/<package_name>`` is :func:`get_package_share_directory`."""
    return str(Path(get_package_share_directory(package_name)).parents[1])


def get_package_share_directory(package_name: str, print_warning: bool = True) -> str:
    from ..project import data_files

    with _lock:
        if package_name in _made:
            return str(_made[package_name])
        source = _package_folder(package_name)
        prefix = f"share/{package_name}"
        installed = [(folder.rstrip("/")[len(prefix):].lstrip("/"), files) for folder, files in data_files(source)
                     if folder.rstrip("/") == prefix or folder.startswith(f"{prefix}/")]
        if not installed and not (source / "setup.py").is_file():
            _made[package_name] = source
            return str(source)
        share = _share_root() / package_name / "share" / package_name
        for below, files in installed:  # share/<pkg>/launch, share/<pkg>/config, ... as colcon lays them out
            (share / below).mkdir(parents=True, exist_ok=True)
            for relative in files:
                link = share / below / Path(relative).name
                if not link.exists():
                    link.symlink_to((source / relative).resolve())
        _made[package_name] = share
        return str(share)


__all__ = ["PackageNotFoundError", "get_package_prefix", "get_package_share_directory"]
