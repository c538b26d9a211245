"""Shared memory state another account, or a crash, has had its hands on: hetros's and iceoryx2's files in
/dev/shm are named with a secret of the user's private folder and closed to other accounts; a node counter
another account made under those names is never trusted (the names are renewed, in one line); a damaged one
of the user's own is replaced. Each trial ends in a launch that starts, its clean-up within seconds.

The second account is ``nobody``, reached by root's setuid (the tests skip where they do not run as root).
"""

from __future__ import annotations

import os
import pwd
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "talker_listener"
TRIALS = 30 if os.environ.get("HETROS_SOAK") == "1" else 4


def _nobody() -> int | None:
    try:
        return pwd.getpwnam("nobody").pw_uid if os.getuid() == 0 else None
    except KeyError:
        return None


NOBODY = _nobody()
needs_second_account = pytest.mark.skipif(NOBODY is None, reason="needs root and the account 'nobody'")


def _as_nobody(code: str) -> subprocess.CompletedProcess[str]:
    assert NOBODY is not None

    def drop() -> None:
        os.setgid(NOBODY)
        os.setuid(NOBODY)
    return subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True, timeout=30, check=False,
                          preexec_fn=drop, cwd="/")


def _project(folder: Path) -> Path:
    (folder / "nodes.py").write_text((EXAMPLE / "nodes.py").read_text())
    project = folder / "project.yaml"
    project.write_text((EXAMPLE / "project.yaml").read_text())
    return project


def _launch(project: Path, duration: float) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(project), "--duration", str(duration)],
                            cwd=project.parent, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            env=dict(os.environ, XDG_RUNTIME_DIR=str(project.parent)), start_new_session=True)


def _counters(folder: Path) -> list[Path]:
    secret = (folder / "hetros" / "shm-name").read_text().strip()
    return sorted(Path("/dev/shm").glob(f"hx{os.getuid()}{secret}_*global_mgmt"))


def _wait_for_counter(folder: Path, launch: subprocess.Popen[str]) -> Path:
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        if (folder / "hetros" / "shm-name").exists() and (found := _counters(folder)):
            return found[0]
        assert launch.poll() is None, launch.communicate()[0]
        time.sleep(0.05)
    raise AssertionError("no node counter appeared")


@needs_second_account
def test_another_account_can_neither_overwrite_nor_forge_the_node_counter(tmp_path: Path) -> None:
    project = _project(tmp_path)
    first = _launch(project, 6)
    try:
        counter = _wait_for_counter(tmp_path, first)
        time.sleep(0.5)
        assert stat.S_IMODE(counter.stat().st_mode) == 0o600, oct(counter.stat().st_mode)
        tried = _as_nobody(f"open({str(counter)!r}, 'r+b').write(b'\\xff' * 16)")
        assert "PermissionError" in tried.stderr, tried.stderr
        out, _ = first.communicate(timeout=60)
    finally:
        first.kill()
    assert first.returncode == 0, out
    # the names seen while it ran, taken by the other account the moment the file is gone
    counter.unlink(missing_ok=True)
    made = _as_nobody(textwrap.dedent(f"""
        import os
        fd = os.open({str(counter)!r}, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
        os.write(fd, b'\\xff' * 16)
        os.fchmod(fd, 0o666)
    """))
    assert made.returncode == 0, made.stderr
    try:
        second = _launch(project, 3)
        out, _ = second.communicate(timeout=60)
        assert second.returncode == 0, out
        assert out.count("I heard") >= 5, out
        assert f"belongs to user {NOBODY}, not to you" in out, out
        assert counter not in _counters(tmp_path)
    finally:
        counter.unlink(missing_ok=True)


@pytest.mark.timeout(60 + 30 * TRIALS)  # two launches a trial: the limit is the work's
def test_a_crash_with_a_damaged_node_counter_is_followed_by_a_launch_that_starts(tmp_path: Path) -> None:
    """Each trial: a launch runs, its node counter is filled with garbage, and the launch is killed as a crash
    kills it; the next launch cleans up and starts, hearing its talker."""
    project = _project(tmp_path)
    for trial in range(TRIALS):
        crashed = _launch(project, 30)
        try:
            counter = _wait_for_counter(tmp_path, crashed)
            time.sleep(0.3)
            with counter.open("r+b") as handle:
                handle.write(os.urandom(16) if trial % 2 else b"\xff" * 16)
        finally:
            os.killpg(crashed.pid, signal.SIGKILL)
            crashed.communicate(timeout=30)
        started = time.monotonic()
        after = _launch(project, 2)
        out, _ = after.communicate(timeout=120)
        assert after.returncode == 0, f"trial {trial}: {out}"
        assert out.count("I heard") >= 3, f"trial {trial}: {out}"
        assert time.monotonic() - started < 10 + 2 + 10, f"trial {trial}: clean-up and start took too long:\n{out}"


_HANDSHAKE = ("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
              "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n"
              "Sec-WebSocket-Protocol: foxglove.websocket.v1\r\n\r\n")
_CLIENT = textwrap.dedent("""
    import socket, sys, time
    sock = socket.create_connection(("127.0.0.1", int(sys.argv[1])), timeout=10)
    sock.sendall(sys.argv[2].encode())
    got = b""
    end = time.monotonic() + 8
    while time.monotonic() < end and b"serverInfo" not in got:
        try:
            chunk = sock.recv(65536)
        except OSError:
            break
        if not chunk:
            break
        got += chunk
    sys.stdout.write(repr(got))
""")


@needs_second_account
def test_foxglove_serves_its_owner_and_refuses_another_account_on_loopback(tmp_path: Path) -> None:
    """Loopback is open to every account: the front port reads the peer's uid from the kernel's socket table."""
    import re

    pytest.importorskip("foxglove")
    project = _project(tmp_path)
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    graph = _launch(project, 40)
    _wait_for_counter(tmp_path, graph)
    time.sleep(1.0)
    server = subprocess.Popen([sys.executable, "-m", "hetros", "foxglove", "--port", "0"], env=env, text=True,
                              cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert server.stdout is not None
        deadline = time.monotonic() + 60
        url = None
        while url is None and time.monotonic() < deadline:
            line = server.stdout.readline()
            url = re.search(r"ws://127\.0\.0\.1:(\d+)", line)
            assert line or server.poll() is None, server.stderr.read() if server.stderr else ""
        assert url is not None
        port = url.group(1)
        (tmp_path / "client.py").write_text(_CLIENT)
        (tmp_path / "client.py").chmod(0o644)
        os.chmod(tmp_path, 0o755)
        mine = subprocess.run(["/usr/bin/python3", str(tmp_path / "client.py"), port, _HANDSHAKE], capture_output=True,
                              text=True, timeout=30, check=False)
        assert "101 Switching Protocols" in mine.stdout and "serverInfo" in mine.stdout, mine.stdout + mine.stderr
        theirs = _as_nobody(f"import sys; sys.argv = ['c', {port!r}, {_HANDSHAKE!r}]\n" + _CLIENT)
        assert "serverInfo" not in theirs.stdout, theirs.stdout
        assert "\\\\x03\\\\xf0" in theirs.stdout or "\\x03\\xf0" in theirs.stdout, theirs.stdout + theirs.stderr
    finally:
        server.terminate()
        server.communicate(timeout=30)
        os.killpg(graph.pid, signal.SIGINT)
        graph.communicate(timeout=60)
