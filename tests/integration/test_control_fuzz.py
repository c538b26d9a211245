"""The control sockets of a running launch under a flood of malformed requests.

Every request is checked before it reaches a node (finite rates in range, names that are text,
known topics, the topic's type for ``pub``) and refused with an error to the client: 0 node
crashes, 0 graph stops, and the graph's own traffic goes on.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import random
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from hetros.launch.observe._control import receive_frame, short_path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "talker_listener" / "project.yaml"
_FRAME = struct.Struct("<II")
_NASTY: list[Any] = [math.nan, math.inf, -math.inf, 1e-320, -1, 0, 2**70, 1e308, "", "x" * 5000, None, True, [],
                     {}, {"a": 1}, "/chatter", "/nowhere", "std_msgs/msg/Int32", "std_msgs/msg/String", 1.5]


def _request(rng: random.Random) -> tuple[bytes, bytes]:
    op = rng.choice(["tap", "pub", "call", "send_goal", "params", "set_param", "stats", "nope", 7, None])
    request: dict[str, Any] = {"op": op}
    for key in rng.sample(["topic", "type", "max_rate", "wait", "timeout", "service", "action", "node", "name",
                           "value", "data"], rng.randrange(0, 6)):
        request[key] = rng.choice(_NASTY)
    if op == "tap" and isinstance(request.get("max_rate"), int | float) and rng.random() < 0.5:
        request["max_rate"] = rng.choice([math.nan, 1e-320, -5.0, 1e12])
    if op == "pub":  # the right topic with a wrong type, or garbage bytes for the right one
        request.setdefault("topic", "/chatter")
        request.setdefault("type", rng.choice(["std_msgs/msg/Int32", "std_msgs/msg/String"]))
    header = json.dumps(request).encode()  # NaN and Infinity go out as JSON's extension, as a forger may
    payload = rng.randbytes(rng.randrange(0, 64))
    if rng.random() < 0.05:  # a frame that lies about its sizes
        return _FRAME.pack(rng.randrange(2**32), rng.randrange(2**32)) + header, b""
    return _FRAME.pack(len(header), len(payload)) + header, payload


def test_ten_thousand_malformed_control_requests_stop_nothing(tmp_path: Path) -> None:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLE), "--duration", "40"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    try:
        sockets = _wait_for_sockets(tmp_path)
        rng = random.Random(34)
        answered = errors = count = 0
        started = time.monotonic()
        # at least 10,000 requests, and for at least 8 s, so that the talker's traffic has time to show
        while count < 10_000 or time.monotonic() - started < 8:
            assert time.monotonic() - started < 30, f"only {count} requests in 30 s"
            assert launch.poll() is None, "the launch stopped under the fuzz"
            count += 1
            frame, payload = _request(rng)
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock, short_path(rng.choice(sockets)) as name:
                sock.settimeout(2.0)
                sock.connect(name)
                try:
                    sock.sendall(frame + payload)
                    answer, _ = receive_frame(sock)
                    answered += 1
                    errors += "error" in answer
                except (OSError, Exception):  # a frame the server hung up on, or a tap that streams
                    pass
        fuzzed = time.monotonic() - started
        assert answered > 5_000 and errors > 2_000
    finally:
        launch.send_signal(signal.SIGINT)  # an orderly stop: the graph must still be whole
        output, _ = launch.communicate(timeout=120)
    assert launch.returncode == 0, output
    assert "Traceback" not in output and "raised" not in output
    heard = [line for line in output.splitlines() if "I heard" in line]
    # the graph's traffic went on throughout: two listeners of a 10 Hz talker, at least half the rate
    assert len(heard) >= 0.5 * 2 * 10 * fuzzed, (len(heard), fuzzed)


def _wait_for_sockets(folder: Path) -> list[Path]:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        found = sorted((folder / "hetros" / "launches").glob("*/cluster*.sock"))
        if len(found) == 2:
            time.sleep(0.5)
            return found
        time.sleep(0.1)
    raise AssertionError("the launch's control sockets never appeared")


def _threads(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Threads:"):
            return int(line.split()[1])
    raise AssertionError("no thread count")


def test_idle_connections_and_huge_claims_cost_a_worker_bounded_threads_and_memory(tmp_path: Path) -> None:
    """2,000 connections that never send a request: the worker holds at most MAX_CONNECTIONS threads for them,
    answers the rest "busy", drops the idle ones after REQUEST_SECONDS, and then serves a good look; a frame
    claiming a payload past the limit is refused before anything is allocated."""
    from hetros.launch.observe._control import MAX_CONNECTIONS, MAX_PAYLOAD, REQUEST_SECONDS

    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    launch = subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLE), "--duration", "60"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    idle: list[socket.socket] = []
    try:
        path = _wait_for_sockets(tmp_path)[0]
        worker = _ask(path, {"op": "stats"})["pid"]
        before = _threads(worker)
        busy = 0
        with short_path(path) as name:
            for _ in range(2_000):
                sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
                sock.settimeout(5.0)
                for _attempt in range(500):  # the listen backlog is short: wait for the accept loop
                    try:
                        sock.connect(name)
                        break
                    except BlockingIOError:
                        time.sleep(0.002)
                idle.append(sock)
            time.sleep(1.0)
            assert _threads(worker) <= before + MAX_CONNECTIONS + 2, (_threads(worker), before)
            for sock in idle[MAX_CONNECTIONS + 50:MAX_CONNECTIONS + 60]:
                with_answer = receive_frame(sock)[0]
                busy += "serves" in with_answer.get("error", "")
            assert busy == 10
            time.sleep(REQUEST_SECONDS + 1.0)
            assert _threads(worker) <= before + 2, (_threads(worker), before)
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as huge:
                huge.settimeout(5.0)
                huge.connect(name)
                huge.sendall(_FRAME.pack(2, MAX_PAYLOAD + 1) + b"{}")
                with contextlib.suppress(OSError):
                    assert huge.recv(1) == b""  # closed, nothing allocated
            assert "nodes" in _ask(path, {"op": "stats"})
    finally:
        for sock in idle:
            sock.close()
        launch.send_signal(signal.SIGINT)
        output, _ = launch.communicate(timeout=120)
    assert launch.returncode == 0, output


def _ask(path: Path, request: dict[str, Any]) -> dict[str, Any]:
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as sock, short_path(path) as name:
        sock.settimeout(10.0)
        sock.connect(name)
        header = json.dumps(request).encode()
        sock.sendall(_FRAME.pack(len(header), 0) + header)
        return receive_frame(sock)[0]
