"""Another process of the user scribbles over a running graph's credits files (every word all ones, or
random): no node dies, and the listener's rate over the next six seconds stays within 20 % of the rate
before. The talker publishes on a timer at 50 Hz, far below what the machine moves, so a rate that drops
is a stall the damage caused, not the machine's load."""

from __future__ import annotations

import json
import mmap
import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from hetros.transport.shm._credits import Credits

NODES = textwrap.dedent("""
    import json, time
    from hetros.interfaces.std_msgs.msg import String


    def talker(node):
        pub = node.create_publisher(String, '/chatter')
        node.create_timer(0.02, lambda: pub.publish(String(data='x')))
        node.spin()


    def listener(node):
        out = open(node.get_parameter('out'), 'a', buffering=1)
        node.create_subscription(String, '/chatter', lambda m: out.write(json.dumps(time.monotonic()) + '\\n'))
        node.spin()
""")


def _credits_files(session_pid: int) -> list[Path]:
    return [path for path in Path("/dev/shm").glob(f"hetros-{session_pid}x*")
            if path.stat().st_size == Credits.SIZE]


@pytest.mark.parametrize("damage", ["all_ones", "random"])
def test_forged_credits_stop_no_node_and_keep_the_rate(damage: str, tmp_path: Path) -> None:
    (tmp_path / "nodes.py").write_text(NODES)
    received = tmp_path / "received.jsonl"
    (tmp_path / "project.yaml").write_text(textwrap.dedent(f"""
        name: forged
        targets: {{a: {{kind: process}}, b: {{kind: process}}}}
        nodes:
          talker: {{run: nodes:talker, target: a, publish: {{/chatter: std_msgs/msg/String}}}}
          listener: {{run: nodes:listener, target: b, subscribe: {{/chatter: std_msgs/msg/String}},
                     parameters: {{out: '{received}'}}}}
        topics:
          /chatter: {{reliability: reliable, history: keep_all, depth: 10}}
    """))
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"),
                               "--duration", "14"], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, env=dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path)))
    try:
        deadline = time.monotonic() + 30
        while (not received.exists() or received.stat().st_size < 400) and time.monotonic() < deadline:
            time.sleep(0.1)
        time.sleep(3.0)
        files = _credits_files(launch.pid)
        assert files, "the launch's credits files were not found"
        forged_at = time.monotonic()
        rng = np.random.default_rng(7)
        for path in files:
            with path.open("r+b") as handle, mmap.mmap(handle.fileno(), Credits.SIZE) as mapped:
                words = np.frombuffer(mapped, dtype="<u8")
                words[:] = 2**64 - 1 if damage == "all_ones" else rng.integers(0, 2**64 - 1, words.size,
                                                                              dtype=np.uint64, endpoint=True)
                del words
        out, _ = launch.communicate(timeout=60)
    finally:
        launch.kill()
    assert launch.returncode == 0, out
    assert "raised" not in out and "Traceback" not in out, out
    times = [json.loads(line) for line in received.read_text().splitlines()]
    before = sum(forged_at - 3.0 <= t < forged_at for t in times) / 3.0
    after = sum(forged_at + 0.5 <= t < forged_at + 6.5 for t in times) / 6.0
    assert before > 20, (before, out[-2000:])
    assert abs(after - before) <= 0.2 * before, f"{before:.1f}/s before the damage, {after:.1f}/s after:\n{out[-3000:]}"
