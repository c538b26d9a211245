"""What crashed launches leave in this user's shared memory, removed without ever risking the launcher.

A node's records under iceoryx2's root (``nodes/<id>/``: its details, one ``.service_tag``
per service it used, one ``.port_tag`` per port) name everything it owned: its ports' data
segments and connections in ``/dev/shm`` carry the port ids, and a service no live node uses
any more is its static config (``services/``) and dynamic segment (named by the service's
unique id). iceoryx2 cleans a dead node itself in a child process (``_stale_child.py``); a
node it cannot clean (it crashed on a damaged segment) is removed here by those paths, and the
log says which, and why.
"""

from __future__ import annotations

import os
import re
import shutil
import signal
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from ..._process import pid_alive
from ._iceoryx import iceoryx_root, log, new_node, node_counters
from ._sample import SHM_DIR, file_prefix, remove_unfinished_segments, renew_file_prefix

_CHILD = Path(__file__).with_name("_stale_child.py")
# iceoryx2's node counter: two words
_COUNTER_SIZE = 16
# a node folder whose details cannot be read is a node that died while being made, once this old
_UNREADABLE_AGE = 30.0
# iceoryx2 cleans a dead node in milliseconds; one that takes longer is stuck on a damaged segment, which
# is then removed by path (a launch after a crash starts within seconds, not minutes)
_CHILD_TIMEOUT = 4.0
_DETAILS_LIMIT = 1 << 16


@dataclass(frozen=True)
class NodeRecord:
    """A node as its folder under iceoryx2's root describes it."""

    node_id: str
    name: str  # "" when its details could not be read
    pid: int  # 0 likewise

    def describe(self) -> str:
        return f"iceoryx2 node {self.name or self.node_id}" + (f" (pid {self.pid})" if self.pid else "")


def recorded_nodes(root: Path) -> list[NodeRecord]:
    """Every node with a folder under ``root``, as its details file tells (read, never trusted)."""
    nodes = []
    try:
        folders = [entry for entry in (root / "nodes").iterdir() if entry.is_dir() and entry.name.isdigit()]
    except OSError:
        return []
    for folder in folders:
        name, pid = "", 0
        try:
            with open(folder / f"{file_prefix()}node.details", "rb") as handle:
                text = handle.read(_DETAILS_LIMIT).decode("utf-8", "replace")
            if found := re.search(r'^name = "([^"\n]{0,200})"', text, re.MULTILINE):
                name = found.group(1)
            if found := re.search(r"^process = ([0-9]{1,10})$", text, re.MULTILINE):
                pid = int(found.group(1))
        except OSError:
            pass
        nodes.append(NodeRecord(folder.name, name, pid))
    return nodes


def _dead(root: Path, node: NodeRecord) -> bool:
    if node.pid:
        return not pid_alive(node.pid)
    try:
        return time.time() - (root / "nodes" / node.node_id).stat().st_mtime > _UNREADABLE_AGE
    except OSError:
        return False


def _remove(path: Path, removed: list[str]) -> None:
    try:
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
        removed.append(str(path))
    except FileNotFoundError:
        pass
    except OSError as exc:
        log.warning("could not remove %s (%s)", path, exc.strerror)


def _service_id(static_config: Path) -> int | None:
    """The unique id a service's dynamic segment is named by (from its static config)."""
    try:
        with open(static_config, "rb") as handle:
            text = handle.read(_DETAILS_LIMIT).decode("utf-8", "replace")
    except OSError:
        return None
    section = text.partition("[unique_service_id]")[2]
    payload = re.search(r"^payload_value = ([0-9]{1,20})$", section, re.MULTILINE)
    unique = re.search(r"^unique_value = ([0-9]{1,20})$", section, re.MULTILINE)
    if payload is None or unique is None:
        return None
    return (int(unique.group(1)) << 64) | int(payload.group(1))


def remove_node_files(root: Path, node: NodeRecord) -> list[str]:
    """Remove a dead node's records, its ports' segments, and the services only it used, by path."""
    folder = root / "nodes" / node.node_id
    removed: list[str] = []
    tags = list(folder.glob(f"{file_prefix()}*_tag")) if folder.is_dir() else []
    ports = [t.name[len(file_prefix()):-len(".port_tag")] for t in tags if t.name.endswith(".port_tag")]
    services = [t.name[len(file_prefix()):-len(".service_tag")] for t in tags if t.name.endswith(".service_tag")]
    _remove(folder, removed)
    for path in (root / "nodes").glob(f"{file_prefix()}{node.node_id}.*"):
        _remove(path, removed)
    for port in filter(str.isdigit, ports):
        for path in [*SHM_DIR.glob(f"{file_prefix()}*_{port}*"), *root.glob(f"{file_prefix()}{port}.*")]:
            _remove(path, removed)
    others = _tagged_services(root)
    for service in services:
        if re.fullmatch(r"[0-9a-f]{40}", service) and service not in others:  # else a live node uses it still
            _remove_service(root, root / "services" / f"{file_prefix()}{service}.service", removed)
    return removed


def _tagged_services(root: Path) -> set[str]:
    """The services some node (alive or not yet cleaned) says it uses."""
    return {tag.name[len(file_prefix()):-len(".service_tag")]
            for tag in (root / "nodes").glob(f"*/{file_prefix()}*.service_tag")}


def _remove_service(root: Path, static_config: Path, removed: list[str]) -> None:
    unique = _service_id(static_config)
    if unique is not None:
        for path in SHM_DIR.glob(f"{file_prefix()}*_{unique}.dynamic"):
            _remove(path, removed)
    _remove(static_config, removed)


# a service is made before its node records using it: one no node names is an orphan once this old
_ORPHAN_AGE = 10.0


def remove_orphaned_services(root: Path, older_than: float = _ORPHAN_AGE) -> list[str]:
    """Services that no node uses any more, left when their nodes' clean-up failed half-way
    (their dynamic segments are often the damaged ones: listing them crashes iceoryx2)."""
    removed: list[str] = []
    used = _tagged_services(root)
    now = time.time()
    for static_config in (root / "services").glob(f"{file_prefix()}*.service"):
        service = static_config.name[len(file_prefix()):-len(".service")]
        try:
            old = now - static_config.stat().st_mtime >= older_than
        except OSError:
            continue
        if old and service not in used:
            _remove_service(root, static_config, removed)
    return removed


def _clean_with_iceoryx(root: Path, dead: dict[str, NodeRecord]) -> list[str]:
    """Let iceoryx2 clean ``dead`` nodes in child processes; remove by path each one it crashes on
    (or that it leaves); returns what was cleaned, one line each."""
    import subprocess  # the launcher's part: a worker, which imports this module, never starts a child

    cleaned: list[str] = []
    left = dict(dead)
    for _attempt in range(len(dead) + 1):
        if not left:
            break
        try:
            child = subprocess.run([sys.executable, str(_CHILD), f"{root}/", file_prefix(), *left], capture_output=True,
                                   text=True, timeout=_CHILD_TIMEOUT, stdin=subprocess.DEVNULL, check=False)
            output, code = child.stdout, child.returncode
        except subprocess.TimeoutExpired as exc:
            partial = exc.stdout or b""  # bytes, whatever text= said
            output, code = partial.decode() if isinstance(partial, bytes) else partial, None
        begun = None
        for line in output.splitlines():
            word, _, node_id = line.partition(" ")
            if node_id not in left:
                continue
            if word == "begin":
                begun = node_id
            elif word == "done":
                cleaned.append(f"{left.pop(node_id).describe()}: dead, cleaned by iceoryx2")
                begun = None
            elif word == "alive":
                left.pop(node_id)  # iceoryx2 sees it alive (its pid was taken by a new process): not ours to touch
        if code == 0 and begun is None:
            break
        if begun is None:
            continue
        node = left.pop(begun)
        why = ("ran past 30 s" if code is None else
               f"died of {signal.Signals(-code).name}" if code < 0 and -code in signal.Signals._value2member_map_
               else f"failed (exit {code})")
        paths = remove_node_files(root, node)
        line = (f"{node.describe()}: iceoryx2 {why} cleaning it (a segment damaged when its process crashed); "
                f"removed its {len(paths)} files by path")
        log.warning("stale shared memory: %s", line)
        cleaned.append(line)
    for node in left.values():  # iceoryx2 did not list them: a folder its listing skips
        paths = remove_node_files(root, node)
        line = f"{node.describe()}: dead, not listed by iceoryx2; removed its {len(paths)} files by path"
        log.warning("stale shared memory: %s", line)
        cleaned.append(line)
    return cleaned


# how long a crashed launch's workers get to notice their launcher is gone and end (they do within a second)
_ORPHAN_PATIENCE = 5.0


def _wait_for_orphans(root: Path) -> None:
    """Let the workers of a launch whose launcher died (a crash, a kill) end before the clean-up: they
    notice within a second, and until they have, their nodes look alive and their shared memory in use."""
    deadline = time.monotonic() + _ORPHAN_PATIENCE
    while time.monotonic() < deadline:
        orphans = [node for node in recorded_nodes(root) if node.pid and pid_alive(node.pid)
                   and (launcher := _launcher_of(node.name)) is not None and not pid_alive(launcher)]
        if not orphans:
            return
        time.sleep(0.05)


def _launcher_of(node_name: str) -> int | None:
    """The launcher's pid of a hetros node (``hetros-<session>-<process>``, the session led by that pid)."""
    found = re.match(r"hetros-([1-9][0-9]{0,9})x", node_name)
    return int(found.group(1)) if found else None


def _heal_node_counters(alive: bool) -> list[str]:
    """iceoryx2's node counter under this user's names, never trusted blindly: one another account owns
    (it watched the names and made the file when it was gone) makes this user's names new; one of this
    user's with no node of the user alive is made anew, so a damaged one cannot fail every later launch.
    It is made here, by one process: the workers of a launch start at once, and two that make the counter
    together can both fail to get a node id from it."""
    healed: list[str] = []
    for path in node_counters():
        try:
            info = path.lstat()
        except OSError:
            continue
        if info.st_uid != os.getuid():
            prefix = renew_file_prefix()  # the running nodes, if any, keep the old names
            line = (f"{path} belongs to user {info.st_uid}, not to you: this user's shared memory files are named "
                    f"{prefix}* from now on")
            log.warning("shared memory: %s", line)
            healed.append(line)
            break
        if not alive:
            _remove(path, healed)
            if info.st_size != _COUNTER_SIZE:
                log.warning("shared memory: iceoryx2's node counter %s was damaged (%d bytes); made anew", path,
                            info.st_size)
    # a node made and dropped here: the counter is made (or found usable) by this one process
    if _probe_node():
        return healed
    # the counter is there but gives no node id: damaged while nodes of this user still run (a crashed
    # launch's workers winding down), so it cannot be removed under them: this launch takes new names
    prefix = renew_file_prefix()
    line = (f"iceoryx2's node counter under this user's names gives no node id (damaged) while nodes of the user "
            f"still run: this user's shared memory files are named {prefix}* from now on")
    log.warning("shared memory: %s", line)
    healed.append(line)
    _probe_node()
    return healed


def _probe_node() -> bool:
    """Whether a node of this process can be made (and dropped at once: the counter stays, closed to others)."""
    try:
        new_node(f"hetros-counter-{os.getpid()}")
    except Exception as exc:  # iceoryx2's own error types: what failed is said, and the workers say more
        log.info("shared memory: iceoryx2 gave no node id (%s: %s)", type(exc).__name__, exc)
        return False
    return True


def cleanup_stale() -> list[str]:
    """Remove what crashed launches of this user left: dead iceoryx2 nodes, orphaned credits
    files and segments a failure left unfinished. Never raises for what it finds, never crashes."""
    removed = remove_unfinished_segments()
    root = iceoryx_root()
    _wait_for_orphans(root)
    recorded = recorded_nodes(root)
    dead = {node.node_id: node for node in recorded if _dead(root, node)}
    if dead:
        cleaned = _clean_with_iceoryx(root, dead)
        log.info("cleaned up after crashed launches: %s", "; ".join(cleaned))
        removed += cleaned
    if orphans := remove_orphaned_services(root):
        log.info("cleaned up after crashed launches: %d files of services no node uses", len(orphans))
        removed += orphans
    for path in SHM_DIR.glob("hetros-*"):  # credits files: hetros-<session>-<digest>, the session led by its pid
        owner = path.name.split("-")[1].split("x")[0] if path.name.count("-") >= 2 else ""
        try:
            mine = path.lstat().st_uid == os.getuid()
        except OSError:
            continue
        if mine and owner.isdigit() and not pid_alive(int(owner)):
            _remove(path, removed)
    removed += _heal_node_counters(alive=len(dead) < len(recorded))  # last: it may rename what comes next
    return removed
