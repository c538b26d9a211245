"""Which launches run on this machine, for `hetros ps` and the commands that look inside one.

Each launcher writes one small JSON record (session, project, pid, hosts, start time) into a
folder only its user can read or write (``$XDG_RUNTIME_DIR/hetros/launches``, else
``/tmp/hetros-<uid>/launches``, mode 0700, each record 0600) and removes it when it ends. A
record whose launcher is gone (killed, crashed) is dropped by the next reader.
"""

from __future__ import annotations

import json
import os
import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from .._errors import LaunchError
from .._process import pid_alive
from ..plan import Plan


@dataclass(frozen=True)
class LaunchRecord:
    session: str
    project: str  # the project's name
    root: str  # its folder
    pid: int
    started: float  # seconds since the epoch
    hosts: tuple[str, ...]
    host: str  # this machine's share ("" without hosts)


def registry_folder() -> Path:
    """The folder of this user's records, created private when missing; refused when someone else owns it."""
    runtime = os.environ.get("XDG_RUNTIME_DIR")
    base = Path(runtime) / "hetros" if runtime else Path("/tmp") / f"hetros-{os.getuid()}"
    folder = base / "launches"
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    for path in (base, folder):
        status = path.stat()
        if status.st_uid != os.getuid():
            raise LaunchError(f"{path} belongs to user {status.st_uid}, not to you ({os.getuid()}): hetros keeps the "
                              "list of your launches there; remove it or set XDG_RUNTIME_DIR to a folder of yours")
        if status.st_mode & 0o077:
            path.chmod(0o700)
    return folder


def session_folder(session: str) -> Path:
    """The private folder of one launch: its plan (``plan.json``) and each process' control socket."""
    folder = registry_folder() / session
    folder.mkdir(exist_ok=True, mode=0o700)
    return folder


def write_private(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` readable by this user only, whole or not at all."""
    partial = path.with_name(f".{path.name}.partial")
    descriptor = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
        handle.write(text)
    os.replace(partial, path)


def register(session: str, plan: Plan) -> Path:
    """Record this launch (the launcher's pid) until :func:`unregister`."""
    record = LaunchRecord(session, plan.name, plan.root, os.getpid(), time.time(), tuple(plan.hosts),
                          plan.local_host)
    path = registry_folder() / f"{session}.json"
    write_private(path, json.dumps(asdict(record)))
    return path


def unregister(session: str) -> None:
    folder = registry_folder()
    (folder / f"{session}.json").unlink(missing_ok=True)
    shutil.rmtree(folder / session, ignore_errors=True)


def running() -> list[LaunchRecord]:
    """This user's running launches, oldest first; records of launchers that are gone are removed."""
    found = []
    for path in sorted(registry_folder().glob("*.json")):
        try:
            raw = json.loads(path.read_text(encoding="utf-8"))
            record = LaunchRecord(**{**raw, "hosts": tuple(raw["hosts"])})
        except (OSError, ValueError, TypeError, KeyError):
            path.unlink(missing_ok=True)  # unreadable: half written by a launcher that died, or not ours
            continue
        if pid_alive(record.pid):
            found.append(record)
        else:
            unregister(record.session)
    return sorted(found, key=lambda r: r.started)


def format_launches(records: list[LaunchRecord]) -> str:
    if not records:
        return "no hetros launch is running (as this user, on this machine)"
    rows = [("SESSION", "PID", "PROJECT", "HOSTS", "STARTED", "FOLDER")]
    for record in records:
        hosts = ",".join(f"*{h}" if h == record.host else h for h in record.hosts) or "-"
        started = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(record.started))
        rows.append((record.session, str(record.pid), record.project, hosts, started, record.root))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    return "\n".join("  ".join(cell.ljust(width) for cell, width in zip(row, widths, strict=True)).rstrip()
                     for row in rows)
