"""Runs one Python launch file's ``generate_launch_description()`` in an interpreter of its own (the file
is the user's code: it may import anything, and must not hang or pollute ``hetros import``), against
hetros's ``launch`` and ``launch_ros``, and prints what the description starts as JSON.

Request (stdin, JSON): ``file``, ``args`` (launch arguments), ``packages`` (name -> source folder),
``namespace``, ``remap``, ``params`` (the scope an XML file includes it in). Answer (stdout, after
:data:`MARKER`): ``{"records": [...]}`` or ``{"error": "file:line: what"}``."""

from __future__ import annotations

import json
import os
import sys
import traceback
from pathlib import Path
from typing import Any

MARKER = "\n@@hetros-launch@@"


def _user_place(exc: BaseException, file: Path) -> str:
    """The deepest frame of the failure that is in the user's launch files (not hetros's)."""
    here = str(Path(__file__).resolve().parent)
    place = f"{file}:1"
    for frame in traceback.extract_tb(exc.__traceback__):
        if not frame.filename.startswith(here):
            place = f"{frame.filename}:{frame.lineno}"
    return place


def _resolved_files(records: list[dict[str, Any]]) -> None:
    """Paths through a package's share folder (links) as the files they name: the folder goes with us."""
    for record in records:
        if record["kind"] == "include":
            record["file"] = os.path.realpath(record["file"])
        for entry in record.get("parameters", []):
            if "file" in entry:
                entry["file"] = os.path.realpath(entry["file"])


def evaluate(request: dict[str, Any]) -> dict[str, Any]:
    from . import ament_index_python, install
    from .launch import LaunchContext, LaunchFileError
    from .launch._core import visit_all
    from .launch.actions import load_python_launch_file
    from .launch_ros import _packages

    file = Path(request["file"]).resolve()
    for name, folder in request.get("packages", {}).items():
        _packages.known[name] = Path(folder)
        ament_index_python._made[name] = Path(folder)  # its share folder is its source folder
    sys.path.insert(0, str(file.parent))
    install()
    context = LaunchContext(argv=[f"{k}:={v}" for k, v in request.get("args", {}).items()])
    context.launch_configurations.update(request.get("args", {}))
    if request.get("namespace"):
        context.launch_configurations["ros_namespace"] = request["namespace"]
    if request.get("remap"):
        context.launch_configurations["ros_remaps"] = [list(pair) for pair in request["remap"]]
    if request.get("params"):
        context.launch_configurations["global_params"] = [tuple(pair) for pair in request["params"]]
    context.entering(file)
    try:
        visit_all(load_python_launch_file(file, f"{file}:1"), context)
    except LaunchFileError as exc:
        return {"error": str(exc)}
    except SystemExit as exc:
        return {"error": f"{_user_place(exc, file)}: the launch file exited ({exc.code})"}
    except Exception as exc:
        return {"error": f"{_user_place(exc, file)}: {type(exc).__name__}: {exc}"}
    _resolved_files(context.records)
    return {"records": context.records}


def main() -> None:
    request = json.loads(sys.stdin.read())
    answer = evaluate(request)
    sys.stdout.write(MARKER + json.dumps(answer, default=str) + "\n")


if __name__ == "__main__":
    main()
