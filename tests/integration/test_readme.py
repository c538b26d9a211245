"""The README is for users: short, and every code block that can run here runs.

A block after ``<!-- file: NAME -->`` is written to NAME in a fresh folder; each line of a
block after ``<!-- run -->`` is then run there as a shell command (``hetros`` being this
interpreter's), and must succeed. The first-hour commands a user types are exercised as well.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"
_BLOCK = re.compile(r"<!-- (file: (?P<name>\S+)|run) -->\n```\w*\n(?P<body>.*?)```", re.S)


def _blocks() -> tuple[dict[str, str], list[str]]:
    files: dict[str, str] = {}
    commands: list[str] = []
    for match in _BLOCK.finditer(README.read_text(encoding="utf-8")):
        if match["name"]:
            files[match["name"]] = match["body"]
        else:
            commands += [line.split("  #", 1)[0].strip() for line in match["body"].splitlines()
                         if line.strip() and not line.startswith("#")]
    return files, commands


def _shell(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "PATH": f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}"}
    return subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=120, check=False)


def test_the_readme_is_short() -> None:
    lines = README.read_text(encoding="utf-8").count("\n")
    assert lines < 350, f"the README has {lines} lines; move detail to docs/"


def test_the_readme_does_not_point_outside_the_repository() -> None:
    text = README.read_text(encoding="utf-8")
    assert "../shared" not in text
    for target in re.findall(r"\]\(([^)#]+)\)", text):
        if not target.startswith("http"):
            assert (ROOT / target).exists(), f"the README links to {target}, which is not in the repository"


def test_the_readme_code_blocks_run(tmp_path: Path) -> None:
    files, commands = _blocks()
    assert {"nodes.py", "project.yaml"} <= set(files) and len(commands) >= 5
    for name, body in files.items():
        (tmp_path / name).write_text(body, encoding="utf-8")
    outputs = []
    for command in commands:
        shown = command.replace("examples/", f"{ROOT}/examples/")
        done = _shell(shown, tmp_path)
        assert done.returncode == 0, f"README command `{command}` failed:\n{done.stdout}\n{done.stderr}"
        outputs.append(done.stdout + done.stderr)
    launched = next(out for command, out in zip(commands, outputs, strict=True) if "launch" in command)
    assert re.search(r"\[listener\].*hello \d+", launched), launched[-2000:]
    assert "node time on" not in launched, "per-node times are logged with --node-times only"


@pytest.mark.parametrize("command", ["hetros msg list | head -1", "hetros msg show std_msgs/msg/String | head -1"])
def test_a_closed_pipe_ends_quietly(command: str, tmp_path: Path) -> None:
    done = _shell(command, tmp_path)
    assert done.returncode == 0 and "Traceback" not in done.stderr, done.stderr
