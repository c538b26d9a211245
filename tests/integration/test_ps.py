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

from hetros.launch._registry import registry_folder, running

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
