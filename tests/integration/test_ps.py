"""`hetros ps`: the launches running as this user on this machine, each listed while it runs and gone
when it ends; a record a dead launcher left behind is dropped; nobody else can read the list."""

from __future__ import annotations

import json
import os
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from hetros.launch.launcher._registry import registry_folder, running

# it reads or changes state every launch of this account shares (/dev/shm, the launch registry): `make test`
# runs it alone, after the integration tests that run side by side
pytestmark = pytest.mark.machine_wide

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _ps(env: dict[str, str]) -> list[dict[str, object]]:
    done = subprocess.run([sys.executable, "-m", "hetros", "ps", "--json"], capture_output=True, text=True,
                          timeout=60, check=True, env=env)
    listed: list[dict[str, object]] = json.loads(done.stdout)
    return listed


def test_a_running_launch_is_listed_and_gone_when_it_ends(tmp_path: Path) -> None:
    env = dict(os.environ, XDG_RUNTIME_DIR=str(tmp_path))
    with subprocess.Popen([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "talker_listener" / "project.yaml"),
                           "--duration", "6"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env) as proc:
        listed: list[dict[str, object]] = []
        deadline = time.monotonic() + 30
        while not listed and time.monotonic() < deadline:
            listed = _ps(env)
            time.sleep(0.2)
        assert len(listed) == 1, "the launch never appeared in hetros ps"
        (record,) = listed
        assert record["pid"] == proc.pid and record["project"] == "talker_listener"
        assert record["root"] == str((EXAMPLES / "talker_listener").resolve()) and record["hosts"] == []
        assert proc.wait(60) == 0
    assert _ps(env) == []
    text = subprocess.run([sys.executable, "-m", "hetros", "ps"], capture_output=True, text=True, timeout=60,
                          check=True, env=env).stdout
    assert "no hetros launch is running" in text


def test_a_dead_launchers_record_is_dropped_and_the_list_is_private(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    folder = registry_folder()
    assert stat.S_IMODE(folder.stat().st_mode) == 0o700
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True,
                          check=True).stdout.strip()
    (folder / "gone.json").write_text(json.dumps({"session": "gone", "project": "p", "root": "/", "pid": int(dead),
                                                  "started": 0.0, "hosts": [], "host": ""}))
    (folder / "torn.json").write_text("{\"session\": ")
    assert running() == []
    assert not (folder / "gone.json").exists() and not (folder / "torn.json").exists()


def test_a_forged_record_removes_nothing_outside_the_registry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                              caplog: pytest.LogCaptureFixture) -> None:
    """A record names a session, and the session a folder to remove: a record of any path, or of
    numbers that are not a pid or a time, is dropped by name and nothing else is touched."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path / "run"))
    (tmp_path / "run").mkdir(mode=0o700)
    folder = registry_folder()
    victim = tmp_path / "victim"
    victim.mkdir()
    (victim / "keep").write_text("precious")
    dead = 4_000_000  # beyond any pid this machine gives, below PID_MAX: dead
    forged = {
        "abs.json": {"session": str(victim), "pid": dead, "started": 0.0},
        "up.json": {"session": "../../victim", "pid": dead, "started": 0.0},
        "1x0000000000.json": {"session": "1x0000000000", "pid": 1, "started": 1e308},
        "2x0000000000.json": {"session": "2x0000000000", "pid": 2**70, "started": 0.0},
        "3x0000000000.json": {"session": "3x0000000000", "pid": -1, "started": float("nan")},
    }
    for name, fields in forged.items():
        (folder / name).write_text(json.dumps({"project": "p", "root": "/", "hosts": [], "host": "", **fields}))
    os.symlink(victim, folder / "4x0000000000")  # a session folder that is a link to the victim
    (folder / "4x0000000000.json").write_text(json.dumps({"session": "4x0000000000", "project": "p", "root": "/",
                                                          "pid": dead, "started": 0.0, "hosts": [], "host": ""}))
    os.symlink(victim / "keep", folder / "5x0000000000.json")  # a record that is a link
    assert running() == []
    assert (victim / "keep").read_text() == "precious"
    assert sorted(os.listdir(folder)) == []
    for name in forged:
        assert name in caplog.text
    assert "5x0000000000.json" in caplog.text


@pytest.mark.parametrize("squat", ["link", "foreign"])
def test_a_squatted_private_folder_is_one_clear_line(tmp_path: Path, squat: str) -> None:
    """/tmp/hetros-<uid> made first by someone else (another owner, or a link to elsewhere): the
    launch refuses with one line naming the folder and the fix, never a traceback."""
    run = tmp_path / "run"
    run.mkdir(mode=0o700)
    base = run / "hetros"
    if squat == "link":
        (tmp_path / "elsewhere").mkdir()
        os.symlink(tmp_path / "elsewhere", base)
    else:
        if os.getuid() != 0:
            pytest.skip("giving a folder to another user needs root")
        base.mkdir(mode=0o755)
        os.chown(base, 65534, 65534)
    env = dict(os.environ, XDG_RUNTIME_DIR=str(run))
    done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(EXAMPLES / "talker_listener" / "project.yaml"),
                           "--duration", "1"], capture_output=True, text=True, timeout=60, env=env)
    assert done.returncode == 1
    assert "Traceback" not in done.stderr
    expected = "is a link" if squat == "link" else "belongs to user 65534"
    assert expected in done.stderr and str(base) in done.stderr, done.stderr
    assert not list((tmp_path / "elsewhere").iterdir()) if squat == "link" else True
