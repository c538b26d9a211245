"""The DDS edge between hosts is bounded on both sides.

A subscriber that never takes used to grow its process without bound (the edge reader
drained Cyclone into an unbounded queue). Now a reliable keep_all edge holds ``depth``
samples in the reader and the writer waits, then raises after ``publish_timeout``; a
keep_last edge keeps the newest ``depth``. Two real processes over loopback.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.ros2 import free_domain

PEER = Path(__file__).resolve().parent / "dds_edge_peer.py"
# long enough for an unbounded queue to show (3 GB offered) and for the RSS to be seen settled for 20 s
SECONDS = 60.0 if os.environ.get("HETROS_SOAK") else 12.0


@pytest.mark.slow
@pytest.mark.timeout(200)
def test_a_subscriber_that_never_takes_holds_its_memory_flat_while_the_publisher_is_held_back(tmp_path: Path) -> None:
    domain = str(free_domain())
    reader = subprocess.Popen([sys.executable, str(PEER), "reader", domain, str(SECONDS + 8), str(tmp_path / "r.json")],
                              stderr=subprocess.PIPE, text=True)
    writer = subprocess.run([sys.executable, str(PEER), "writer", domain, str(SECONDS), str(tmp_path / "w.json")],
                            capture_output=True, text=True, timeout=SECONDS + 60)
    assert writer.returncode == 0, writer.stderr[-3000:]
    _out, err = reader.communicate(timeout=60)
    assert reader.returncode == 0, err[-3000:]
    sent = json.loads((tmp_path / "w.json").read_text())
    seen = json.loads((tmp_path / "r.json").read_text())
    assert seen["matched"] == [1, 1]
    # 100 Hz of 1 MB: 1.8 GB offered in 18 s; the keep_last edge took it all (a third of the rate at least)
    assert sent["sent_last"] > 33 * SECONDS, sent
    # keep_all: the reader's depth (4) plus the writer's (4), then the writer waits and raises
    assert sent["sent_all"] <= 12, sent
    assert sent["timeouts_all"] >= SECONDS / 1.0 / 2, sent
    assert sent["first_timeout_at"] is not None and sent["first_timeout_at"] < 5, sent
    # the waiting thread sleeps while samples wait in the full reader (it spun a CPU before)
    assert seen["cpu"] < 0.35 * SECONDS, f"the reader used {seen['cpu']:.1f} s of CPU in {SECONDS:g} s"
    rss = seen["rss"]
    settled = rss[10:]  # after start-up and the first samples
    assert max(settled) - min(settled) < 64 * 1024 * 1024, f"reader RSS moved: {[r >> 20 for r in rss]} MiB"
