"""Each node's command line is its own, though nodes share a process: ``sys.argv`` is ``[its script or
module file, *args:]`` for scripts and entry points alike, and a node whose module uses asyncio finds an
event loop in its thread, as a ROS node finds one in its process's main thread."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

NODES = '''
import argparse
import asyncio
import sys
import time

import rclpy


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--name")
    time.sleep(0.2)  # the other node of the process has set its own command line meanwhile
    args = parser.parse_args(sys.argv[1:])
    rclpy.init()
    node = rclpy.create_node(f"argv_{args.name}")
    node.get_logger().info(f"argv {sys.argv[0].rsplit('/', 1)[-1]} {args.name} len={len(sys.argv)}")
    rclpy.shutdown()


async def _answer() -> int:
    await asyncio.sleep(0.01)
    return 42


def uses_asyncio() -> None:
    rclpy.init()
    node = rclpy.create_node("loop_user")
    loop = asyncio.get_event_loop()
    node.get_logger().info(f"asyncio answered {loop.run_until_complete(_answer())}")
    rclpy.shutdown()
'''


def test_each_node_parses_its_own_args_and_finds_an_event_loop(tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(NODES)
    (tmp_path / "script.py").write_text("import sys\nprint('script argv', sys.argv[1:], flush=True)\n")
    (tmp_path / "project.yaml").write_text(textwrap.dedent("""\
        name: argv
        targets: {one: {kind: process}}
        nodes:
          a: {run: nodes:main, target: one, args: [--name, A]}
          b: {run: nodes:main, target: one, args: [--name, B]}
          c: {run: script.py, target: one, args: [x, y]}
          d: {run: nodes:uses_asyncio, target: one}
        """))
    command = [sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration", "20"]
    done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "[argv_A]: argv nodes.py A len=3" in done.stderr
    assert "[argv_B]: argv nodes.py B len=3" in done.stderr
    assert "script argv ['x', 'y']" in done.stdout + done.stderr
    assert "[loop_user]: asyncio answered 42" in done.stderr
    assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr
