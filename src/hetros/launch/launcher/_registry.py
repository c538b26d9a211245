"""Which launches run on this machine, for `hetros ps` and the commands that look inside one.

Each launcher writes one small JSON record (session, project, pid, hosts, start time) into a
folder only its user can read or write (``$XDG_RUNTIME_DIR/hetros/launches``, else
``/tmp/hetros-<uid>/launches``, mode 0700, each record 0600) and removes it when it ends. A
record whose launcher is gone (killed, crashed) is dropped by the next reader.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import stat
import time
from dataclasses import asdict, dataclass
from pathlib import Path

from ..._errors import InputFileError
from ..._files import parse_json
from ..._log import get_logger
from ..._paths import check_session, is_session, private_folder, user_subfolder
from ..._process import pid_alive, valid_pid
from ...plan import Plan

log = get_logger("hetros.launch")


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
    """The folder of this user's records (checked private: ``hetros._paths``)."""
    return user_subfolder("launches")


def session_folder(session: str) -> Path:
    """The private folder of one launch: its plan (``plan.json``) and each process' control socket."""
    return private_folder(registry_folder() / check_session(session))


def write_private(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` readable by this user only, whole or not at all."""
    partial = path.with_name(f".{path.name}.partial")
    descriptor = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
        handle.write(text)
    os.replace(partial, path)


def register(session: str, plan: Plan) -> Path:
    """Record this launch (the launcher's pid) until :func:`unregister`."""
    check_session(session)
    record = LaunchRecord(session, plan.name, plan.root, os.getpid(), time.time(), tuple(plan.hosts),
                          plan.local_host)
    path = registry_folder() / f"{session}.json"
    write_private(path, json.dumps(asdict(record)))
    return path


def unregister(session: str) -> None:
    """Remove a launch's record and its folder: only a folder of a session id's shape, directly in
    the registry, never through a link."""
    if not is_session(session):
        log.warning("launch registry: refused to remove anything by the session id %r (not one of ours)", session)
        return
    folder = registry_folder()
    (folder / f"{session}.json").unlink(missing_ok=True)
    path = folder / session
    try:
        info = os.lstat(path)
    except FileNotFoundError:
        return
    if stat.S_ISDIR(info.st_mode) and info.st_uid == os.getuid():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)  # a link or a file where a launch's folder should be: the name only


# the largest record a launcher writes is a few hundred bytes
_RECORD_LIMIT = 1 << 16


def _read_record(path: Path) -> LaunchRecord:
    """One record, every field checked; ValueError names what is wrong."""
    descriptor = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK)
    with os.fdopen(descriptor, "rb") as handle:
        info = os.fstat(handle.fileno())
        if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid():
            raise ValueError("not a file of yours")
        try:
            raw = parse_json(handle.read(_RECORD_LIMIT), path.name)
        except InputFileError as exc:
            raise ValueError(str(exc)) from None
    if not isinstance(raw, dict):
        raise ValueError("not a JSON object")
    session, pid, started = raw.get("session"), raw.get("pid"), raw.get("started")
    if not is_session(session) or f"{session}.json" != path.name:
        raise ValueError(f"its session {session!r} is not a session id, or not its file's name")
    if not valid_pid(pid) or not isinstance(pid, int):
        raise ValueError(f"its pid {pid!r} is not a process id")
    if isinstance(started, bool) or not isinstance(started, int | float) or not math.isfinite(started) or \
            not 0 <= started <= time.time() + 86_400:
        raise ValueError(f"its start time {started!r} is not a time")
    texts = {key: raw.get(key) for key in ("project", "root", "host")}
    hosts = raw.get("hosts")
    if not all(isinstance(value, str) and len(value) <= 4096 for value in texts.values()) or \
            not isinstance(hosts, list) or not all(isinstance(h, str) and len(h) <= 256 for h in hosts):
        raise ValueError("its project, root, host or hosts are not text")
    return LaunchRecord(str(session), str(texts["project"]), str(texts["root"]), pid, float(started), tuple(hosts),
                        str(texts["host"]))


def running() -> list[LaunchRecord]:
    """This user's running launches, oldest first; records of launchers that are gone are removed,
    and so are records that are not a launcher's (named, with what was wrong)."""
    found = []
    for path in sorted(registry_folder().glob("*.json")):
        try:
            record = _read_record(path)
        except (OSError, ValueError) as exc:
            # unreadable: half written by a launcher that died, or not ours: dropped by its name (a link is
            # not followed); what cannot be (a folder named *.json) is set aside under a name no reader takes
            # for a record. Never fatal to the next command.
            try:
                path.unlink(missing_ok=True)
                log.warning("launch registry: dropped %s (%s)", path.name, exc)
            except OSError:
                aside = path.with_name(f".{path.name}.bad-{time.time_ns()}")
                try:
                    os.rename(path, aside)
                    log.warning("launch registry: %s is not a launch record (%s); moved to %s", path.name, exc,
                                aside.name)
                except OSError as moved:
                    log.warning("launch registry: %s is not a launch record (%s) and cannot be moved aside (%s); "
                                "remove it", path.name, exc, moved.strerror)
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
