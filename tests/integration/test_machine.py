"""The machine around a launch: a full /dev/shm, and two accounts side by side.

Both need root (a private mount namespace for a small tmpfs; a second account), as CI has.
"""

from __future__ import annotations

import os
import pwd
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "talker_listener" / "project.yaml"
root_only = pytest.mark.skipif(os.getuid() != 0 or shutil.which("unshare") is None, reason="needs root and unshare")

# it reads or changes state every launch of this account shares (/dev/shm, the launch registry): `make test`
# runs it alone, after the integration tests that run side by side
pytestmark = pytest.mark.machine_wide


@root_only
@pytest.mark.parametrize("size", ["64k", "1m"])
def test_a_full_dev_shm_is_named_and_exits_1_without_sigbus(size: str) -> None:
    """/dev/shm a small tmpfs (a private mount namespace): the launch refuses with /dev/shm, its free
    space and the size needed, exit 1, no SIGBUS, and leaves nothing in it."""
    script = (f"mount -t tmpfs -o size={size} tmpfs /dev/shm && "
              f"{sys.executable} -m hetros launch {EXAMPLE} --duration 3; code=$?; "
              "echo left: $(ls /dev/shm | grep -v global_mgmt | wc -l); exit $code")
    done = subprocess.run(["unshare", "-m", "--propagation", "private", "sh", "-c", script], capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 1, done.stderr
    assert "/dev/shm has" in done.stderr and "MiB free" in done.stderr and "needs" in done.stderr, done.stderr
    assert "SIGBUS" not in done.stderr and "Traceback" not in done.stderr
    assert "left: 0" in done.stdout


_OTHER = "hetrostest"
# the venv's interpreter may sit in a folder other accounts cannot enter (/root): the other account runs
# the system's Python of the same version on this checkout and the venv's packages
_OTHER_PATH = f"{Path(__file__).resolve().parents[2] / 'src'}:{Path(sysconfig.get_paths()['purelib'])}"


def _other_python() -> list[str]:
    system = Path(f"/usr/bin/python{sys.version_info.major}.{sys.version_info.minor}")
    if not system.exists():
        pytest.skip(f"{system} (the venv's Python version, runnable by another account) is missing")
    return [str(system)]


@pytest.fixture
def other_account() -> str:
    if os.getuid() != 0 or shutil.which("runuser") is None:
        pytest.skip("a second account needs root")
    try:
        pwd.getpwnam(_OTHER)
    except KeyError:
        subprocess.run(["useradd", "--no-create-home", "--shell", "/usr/sbin/nologin", _OTHER], check=True)
    return _OTHER


def _launch_as(user: str | None, duration: str) -> subprocess.Popen[str]:
    env = {key: value for key, value in os.environ.items() if key != "XDG_RUNTIME_DIR"}
    env["PYTHONDONTWRITEBYTECODE"] = "1"
    command = [sys.executable, "-m", "hetros", "launch", str(EXAMPLE), "--duration", duration]
    if user is not None:
        command = ["runuser", "-u", user, "--", "env", "HOME=/tmp", f"PYTHONPATH={_OTHER_PATH}", *_other_python(),
                   *command[1:]]
    return subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd="/tmp")


@pytest.mark.parametrize("first", ["root", "other"])
def test_two_accounts_launch_side_by_side_and_cannot_see_each_other(other_account: str, first: str) -> None:
    """Either account first: both launches run with shared memory and complete; neither can read
    the other's registry, sessions, iceoryx2 records or segments."""
    order = [None, other_account] if first == "root" else [other_account, None]
    procs = [_launch_as(user, "4") for user in order]
    outputs = [proc.communicate(timeout=120)[0] for proc in procs]
    for proc, output in zip(procs, outputs, strict=True):
        assert proc.returncode == 0, output
        assert "I heard: [hello world 5]" in output, output
    uid = pwd.getpwnam(other_account).pw_uid
    theirs = Path(f"/tmp/hetros-{uid}")
    assert theirs.is_dir() and (theirs.stat().st_mode & 0o077) == 0 and theirs.stat().st_uid == uid
    probe = ("import os, sys\n"
             "for path in sys.argv[1:]:\n"
             "    try:\n"
             "        os.listdir(path); print('READ', path)\n"
             "    except PermissionError:\n"
             "        print('refused', path)\n")
    ours = Path(f"/tmp/hetros-{os.getuid()}")
    done = subprocess.run(["runuser", "-u", other_account, "--", *_other_python(), "-c", probe, str(ours / "launches"),
                           str(ours / "iceoryx2")], capture_output=True, text=True, timeout=60)
    assert "READ" not in done.stdout and done.stdout.count("refused") == 2, done.stdout + done.stderr
    for name in os.listdir("/dev/shm"):  # segments: each account's own names, readable by it alone
        info = os.stat(f"/dev/shm/{name}")
        if name.startswith(f"hx{uid}_") and not name.endswith("global_mgmt"):
            assert info.st_uid == uid and info.st_mode & 0o077 == 0, name
