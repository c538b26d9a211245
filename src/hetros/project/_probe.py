"""The node-module probe: each ``run:`` imported in an interpreter of its own, so a module that
raises, hangs or lacks its function is reported by ``hetros check`` without running in it."""

from __future__ import annotations

import importlib.util
import json
import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

from ._model import LoadedProject


def module_findable(project: LoadedProject, module: str) -> bool:
    for folder in project.import_folders:
        candidate = folder.joinpath(*module.split("."))
        if candidate.with_suffix(".py").is_file() or (candidate / "__init__.py").is_file():
            return True
    try:
        return importlib.util.find_spec(module) is not None
    except (ImportError, ValueError):
        return False


_PROBE = """
import importlib, json, sys
from pathlib import Path
from hetros.compat import install
from hetros.msg import registry
types = registry()
for folder in json.loads(sys.argv[2]):
    types.load_folder(Path(folder))
install()  # rclpy and ROS message packages, as a hetros worker serves them
out = {}
for run in json.loads(sys.argv[1]):
    module_name, _, attr = run.partition(":")
    try:
        module = importlib.import_module(module_name)
    except BaseException as exc:
        from hetros.project._probe import import_problem  # only when a module failed: project/ is heavy
        out[run] = import_problem(module_name, exc)
        continue
    target = getattr(module, attr, None)
    if target is None:
        out[run] = f"module {module_name!r} has no {attr!r}; define it or fix 'run: {run}'"
    elif not callable(target):
        out[run] = (f"{run} must be a function or class taking the node, or a ROS main() taking no argument, "
                    f"not {type(target).__name__}")
print("\\n" + sys.argv[3] + json.dumps(out))
"""


# packages of a ROS installation that hetros's rclpy and rospy do not stand in for
_ROS_ONLY = frozenset({"sensor_msgs_py", "rosidl_runtime_py",
                       "rclpy_message_converter", "rosbag", "rosbag2_py",
                       "roslib", "rosgraph", "rostest", "rosunit", "dynamic_reconfigure", "actionlib"})
_SHIM = "hetros.compat."


def import_problem(module_name: str, exc: BaseException) -> str:
    """What ``hetros check`` says when importing a node module raised ``exc``: a piece of ROS hetros does
    not provide is named with the user's line that used it (the module is fine); anything else is the
    module's own error at its innermost line of user code."""
    package = str(Path(__file__).resolve().parents[1])
    place = ""
    tb = exc.__traceback__
    while tb is not None:
        filename = tb.tb_frame.f_code.co_filename
        if not filename.startswith((package, "<")) and "importlib" not in filename:
            place = f"{filename}:{tb.tb_lineno}"
        tb = tb.tb_next
    missing = ""
    if isinstance(exc, ImportError) and exc.name:
        shim = exc.name.startswith(_SHIM)
        name = exc.name.removeprefix(_SHIM)
        if isinstance(exc, ModuleNotFoundError) and (shim or name.split(".")[0] in _ROS_ONLY):
            missing = name
        elif shim and (quoted := re.search(r"cannot import name '([^']+)'", str(exc))):
            missing = f"{name}.{quoted[1]}"
        elif re.fullmatch(r"\w+\.(msg|srv|action)", name) and \
                (quoted := re.search(r"cannot import name '([^']+)'", str(exc))):
            typename = f"{name.replace('.', '/')}/{quoted[1]}"
            return (f"{place or module_name}: uses {typename}, a type hetros does not know; add the folder of the "
                    f"package that defines it to messages: (`hetros msg show` lists the known ones)")
    if missing:
        return (f"{place or module_name}: uses {missing}, which hetros does not provide (its rclpy and rospy cover "
                "what docs/GUIDE.md lists); the module is fine as ROS code: drop that use under hetros, or run the "
                "node under ROS and join it through external:")
    where = f" ({place})" if place else ""
    return f"importing {module_name!r} raised {type(exc).__name__}: {exc}{where}; fix the module"


# the probe's answer line starts with this: a node module that prints, or ends the interpreter
# at import, cannot be taken for the answer
_PROBE_MARK = "hetros-probe-result: "


_probed: dict[tuple[str, tuple[str, ...], tuple[float, ...]], dict[str, str]] = {}


class _ProbeEnded(Exception):
    """The probe gave no answer: it timed out (``timed_out``), or its interpreter ended (``reason``)."""

    def __init__(self, reason: str, timed_out: bool) -> None:
        super().__init__(reason)
        self.reason, self.timed_out = reason, timed_out


def _probe(project: LoadedProject, program: str, arguments: list[str], timeout: float) -> dict[str, str]:
    """Run ``program`` in an interpreter of its own, in the project's folder and on its import path;
    its answer is the last line that starts with the mark (its mapping of keys to problems)."""
    root = str(project.root.resolve())
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [*map(str, project.import_folders), env.get("PYTHONPATH", "")]))
    try:
        done = subprocess.run([sys.executable, "-c", program, *arguments], capture_output=True, text=True,
                              timeout=timeout, env=env, cwd=root, check=False)
    except subprocess.TimeoutExpired:
        raise _ProbeEnded("", timed_out=True) from None
    answers = [line[len(_PROBE_MARK):] for line in done.stdout.splitlines() if line.startswith(_PROBE_MARK)]
    try:
        problems = json.loads(answers[-1])
        if not isinstance(problems, dict):
            raise ValueError(problems)
    except (ValueError, IndexError):
        reason = (done.stderr.strip().splitlines() or [f"exit code {done.returncode}, no error printed"])[-1]
        raise _ProbeEnded(reason, timed_out=False) from None
    return {str(key): str(value) for key, value in problems.items()}


def runnable_problems(project: LoadedProject, runs: list[str]) -> dict[str, str]:
    """Import every node module as the launch will, in a separate interpreter, and find the nodes.

    A separate process keeps the user's import-time code (and module names that differ
    between projects, like many a ``nodes``) out of the checking process.
    """
    if not runs:
        return {}
    root = str(project.root.resolve())
    stamps = tuple(p.stat().st_mtime for folder in project.import_folders for p in sorted(folder.glob("**/*.py")))
    key = (root, tuple(sorted(runs)), stamps)
    if key in _probed:
        return _probed[key]
    folders = [str((project.root / m).resolve()) for m in project.model.messages]
    try:
        problems = _probe(project, _PROBE, [json.dumps(sorted(runs)), json.dumps(folders), _PROBE_MARK], 60)
    except _ProbeEnded as ended:
        if ended.timed_out:
            return {run: "importing the node modules took more than 60 s; does a module block on import?"
                    for run in runs}
        problems = {run: f"importing the node modules ended the interpreter before hetros could look at "
                         f"them ({ended.reason}); does a module exit or kill its process at import?" for run in runs}
    _probed[key] = problems
    return problems


_HW_PROBE = """
import json, sys
try:
    from hetros.hw.nodes import make_hardware_node, port_problems
except ImportError as exc:
    print("\\n" + sys.argv[2] + json.dumps({"": f"cannot check hardware nodes: {exc}"}))
    raise SystemExit(0)
out = {}
for job in json.loads(sys.argv[1]):
    try:
        component = make_hardware_node(job["hw"], ".", job["data_width"], job["parameters"])
        problems = port_problems(component, job["publish"], job["subscribe"], job["data_width"], job["services"],
                                 memory=bool(job.get("memory")))
    except BaseException as exc:
        problems = [f"making it raised {type(exc).__name__}: {exc}"]
    if problems:
        out[job["node"]] = "; ".join(problems)
print("\\n" + sys.argv[2] + json.dumps(out))
"""


def hardware_problems(project: LoadedProject) -> dict[str, str]:
    """Each ``hw:`` node on an fpga target whose component does not fit its topics (missing, extra or
    mis-shaped ports), made in an interpreter of its own as the node modules are; under the key ""
    why the check could not run (the hardware tools are not installed)."""
    model = project.model
    jobs: list[dict[str, Any]] = [{"node": name, "hw": spec.hw, "data_width": model.targets[spec.target].data_width,
             "parameters": spec.parameters, "publish": list(spec.types("publish")),
             "subscribe": list(spec.types("subscribe")), "services": list(spec.types("services")),
             "memory": list(spec.memory)}
            for name, spec in model.nodes.items()
            if spec.hw and spec.target in model.targets and model.targets[spec.target].kind == "fpga"]
    if not jobs:
        return {}
    try:
        return _probe(project, _HW_PROBE, [json.dumps(jobs), _PROBE_MARK], 120)
    except _ProbeEnded as ended:
        what = "took more than 120 s" if ended.timed_out else f"ended the interpreter ({ended.reason})"
        return {job["node"]: f"making its hardware {what}" for job in jobs}
