"""The layout of a shared-memory sample and the limits of a service (no iceoryx2 needed to test it)."""

from __future__ import annotations

import bisect
import contextlib
import ctypes
import functools
import os
import re
import stat
import struct
import threading
import time
from pathlib import Path
from typing import Any

from ..._errors import MachineError, TransportError
from ..._paths import user_folder
from ..._qos import QoS
from ...msg import wanted as _compiled_wanted
from .._codec import CDR_LE

try:  # the compiled slot buffer (built by pip where a C compiler is); ctypes serves otherwise
    from ._cslot import Memory as _Memory  # type: ignore[import-not-found]
except ImportError:
    _Memory = None
if not _compiled_wanted():
    _Memory = None

SHM_DIR = Path("/dev/shm")
# where the secret part of this user's iceoryx2 file names is kept (in the user's private folder)
_NAME_FILE = "shm-name"
_SECRET = re.compile(r"[0-9a-f]{10}")


def file_prefix() -> str:
    """The start of every file name iceoryx2 makes for this user (in /dev/shm and under its root):
    ``hx<uid><secret>_``. /dev/shm is shared by every account: with a name another account can
    predict, it could make the file first, or fill it with garbage, and every later launch of this
    user failed. The secret lives in the user's private folder, so no other account can know a
    name before it exists (and one that exists is this user's, mode 0600)."""
    return _prefix_in(str(user_folder()))


@functools.cache
def _prefix_in(folder: str) -> str:
    path = Path(folder) / _NAME_FILE
    for _attempt in range(3):
        try:
            with open(path, encoding="ascii") as handle:
                secret = handle.read(64).strip()
            if _SECRET.fullmatch(secret):
                return f"hx{os.getuid()}{secret}_"
        except (OSError, UnicodeDecodeError):
            pass
        _write_secret(path, exclusive=True)
    raise MachineError(f"{path} does not hold the name hetros gives this user's shared memory; remove it")


def _write_secret(path: Path, *, exclusive: bool) -> None:
    """A new secret at ``path``; ``exclusive``: only where there is none (two processes starting at once
    agree on the first one written)."""
    secret = os.urandom(5).hex()
    if exclusive:
        try:
            descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
        except FileExistsError:
            with contextlib.suppress(OSError):
                if not _SECRET.fullmatch(path.read_text(encoding="ascii", errors="replace").strip()):
                    path.unlink()  # damaged: the next attempt writes a new one
            return
        with os.fdopen(descriptor, "w", encoding="ascii") as handle:
            handle.write(secret)
        return
    partial = path.with_name(f".{path.name}.{os.getpid()}")
    descriptor = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_NOFOLLOW, 0o600)
    with os.fdopen(descriptor, "w", encoding="ascii") as handle:
        handle.write(secret)
    os.replace(partial, path)


def renew_file_prefix() -> str:
    """A new secret for this user's iceoryx2 file names (the old names were taken or damaged by another
    account); the new prefix. Only when no node of this user runs: they keep the old names."""
    _write_secret(user_folder() / _NAME_FILE, exclusive=False)
    _prefix_in.cache_clear()
    return file_prefix()
# Every sample: sequence number, publisher slot, layout, when it was sent (CLOCK_MONOTONIC ns,
# one clock for every process of the machine: a lifespan is checked against it), padding; then
# the message. With the CDR layout the 4-byte encapsulation sits at 28..32 so the CDR body
# starts 8-byte aligned.
HEADER = struct.Struct("<QIIQ4x")
CDR_BODY_AT = HEADER.size + len(CDR_LE)
LAYOUT_CDR = 0
LAYOUT_SPLIT = 1
# The split layout (loaned messages): small part as CDR, primitive arrays as separate blobs
# at 64-byte aligned offsets, each named by its index in the type's array list.
SPLIT = struct.Struct("<II")
BLOB = struct.Struct("<IIQQ")
# the table of a message with one array (most loans), read in one unpack
SPLIT_ONE = struct.Struct("<" + SPLIT.format[1:] + BLOB.format[1:])
LOAN_RESERVE = 4096
# Plain messages up to this size are one contiguous CDR (one encode, arrays inline and read
# in place as views); larger ones use the split layout, whose blobs need no zeroing.
INLINE_LIMIT = 64 * 1024
MAX_SUBSCRIBER_SLOTS = 32
MAX_PUBLISHERS_PER_SERVICE = 8
MAX_EVENT_PORTS = 256
# iceoryx2's event latency grows with the id range (measured: 13 µs at 100, 25 µs at 4095,
# 215 µs at 65535), so ids are few; readers beyond that share an id (a spurious wake-up
# costs one empty receive).
MAX_EVENT_ID = 255
INTERRUPT_EVENT = 0
BORROW_LIMIT = 16
# A reader that sees published samples it cannot receive waits this long for a late connection
# before it reports them lost.
LOSS_GRACE = 0.5


INITIAL_SLOT = 4096
# unpublished loans one publisher may hold (a plain publish takes one for a moment too)
MAX_LOANS = 8


def reserved_bytes(qos: QoS, message_size: int | None) -> int:
    """Shared memory one service of a topic reserves (iceoryx2 sizes it up front, sparse).

    ``message_size`` is the CDR size of a fixed-size type, None when it varies: such slots
    start at 4 KiB and grow by powers of two as larger messages come.
    """
    buffer = qos.depth + 2 if qos.blocks_publisher else qos.depth
    history = qos.depth if qos.keeps_history else 0
    samples = MAX_SUBSCRIBER_SLOTS * (buffer + BORROW_LIMIT) + history + MAX_LOANS
    slot = HEADER.size + (message_size + 4 if message_size is not None else INITIAL_SLOT)
    return samples * slot


def check_room(need: int, what: str) -> None:
    """Refuse, with /dev/shm and its free space named, a segment that /dev/shm has no room for.

    iceoryx2 makes segments sparse: one made in a full /dev/shm succeeds, and the first write
    to a page the tmpfs cannot back kills the process with SIGBUS, which names nothing.
    """
    try:
        info = os.statvfs(SHM_DIR)
    except OSError:
        return
    free = info.f_bavail * info.f_frsize
    if free < need:
        raise MachineError(
            f"{SHM_DIR} has {free / 2**20:,.1f} MiB free, and {what} needs {need / 2**20:,.1f} MiB of it (its "
            f"{SHM_DIR} is {info.f_blocks * info.f_frsize / 2**20:,.0f} MiB in all): free some (`df -h {SHM_DIR}`; "
            "a crashed program's files there), make it larger (a container's --shm-size), lower the topic's "
            "depth, or map the nodes to threads of one process")


def segment_prefix(session: str) -> str:
    return f"hetros-{session}-"


# a tag that every session this process starts carries (``new_session``): a test suite sets it
# to find exactly the shared memory it made, whatever else runs on the machine
SESSION_TAG_VARIABLE = "HETROS_SESSION_TAG"


def new_session() -> str:
    """A launch's session name: ``<pid>x<tag><random>``; the pid lets a later launch remove
    what a crashed one left, the tag is ``$HETROS_SESSION_TAG`` (lowercase letters and digits)."""
    tag = os.environ.get(SESSION_TAG_VARIABLE, "")
    if tag and not re.fullmatch(r"[a-wyz0-9]{1,16}", tag):
        raise TransportError(f"{SESSION_TAG_VARIABLE} must be at most 16 lowercase letters (but 'x') and "
                             f"digits, not {tag!r}")
    return f"{os.getpid()}x{tag}{os.urandom(3).hex()}"


_BLOB_TABLES: dict[int, struct.Struct] = {}


def blob_table(count: int) -> struct.Struct:
    """``count`` BLOB entries as one struct (one unpack for the whole table)."""
    table = _BLOB_TABLES.get(count)
    if table is None:
        table = _BLOB_TABLES[count] = struct.Struct("<" + BLOB.format[1:] * count)
    return table


def align(value: int, to: int) -> int:
    return (value + to - 1) & -to


# ctypes array types with room for what keeps a sample alive, by size
_SLOT_TYPES: dict[int, Any] = {}
_LEASE_TYPES: dict[int, Any] = {}


def _sized(cache: dict[int, Any], size: int, mixins: tuple[type, ...], slots: tuple[str, ...]) -> Any:
    """The ctypes byte array type of ``size`` with ``slots`` (cached; types are costly to make)."""
    kind = cache.get(size)
    if kind is None:
        if len(cache) > 4096:  # sizes that keep changing must not grow the cache forever
            cache.clear()
        kind = cache[size] = type("Slot", (*mixins, ctypes.c_uint8 * size), {"__slots__": slots})
    return kind


class _Leased:
    """Mixin of the ctypes view on a received sample: it holds the sample and counts itself.

    ``borrowed`` has one entry per live view (list append and pop are atomic, and the last
    reference to a view may go in any thread); iceoryx2 gets the sample back when it dies.
    """

    __slots__ = ()
    sample: Any
    borrowed: list[None]

    def __del__(self) -> None:
        self.borrowed.pop()


# iceoryx2 creates a segment with mode 0200 and opens it up once it is complete: one still so
# after this long, or larger than the machine's memory could ever hold, was left by a failure
_UNFINISHED_AGE = 30.0


def remove_unfinished_segments(larger_than: int | None = None) -> list[str]:
    """Remove iceoryx2 data segments that were never finished (mode 0200) and never will be:
    older than ``_UNFINISHED_AGE`` s, or, right after a failed growth, larger than ``larger_than``
    bytes (a 3.79 GB sparse file was left behind when memory ran out, and never removed)."""
    removed: list[str] = []
    now = time.time()
    for path in SHM_DIR.glob(f"{file_prefix()}*.data"):
        try:
            info = path.stat()
        except OSError:
            continue
        if info.st_uid != os.getuid() or stat.S_IMODE(info.st_mode) != 0o200:
            continue
        if now - info.st_mtime > _UNFINISHED_AGE or (larger_than is not None and info.st_size > larger_than):
            try:
                path.unlink()
                removed.append(path.name)
            except FileNotFoundError:
                pass
    return removed


class MappedSegments:
    """The address ranges of the iceoryx2 data segments this process has mapped.

    A received sample's place and size come from shared memory, which any process of the
    same user can write: a size past the end of its segment made views (and then array
    reads) of memory that is not mapped, and the process died of SIGSEGV. Each sample is
    checked against these ranges, reread from ``/proc/self/maps`` only when a sample lies
    outside all of them (a segment mapped since).
    """

    def __init__(self) -> None:
        self.ranges: list[tuple[int, int]] = []
        self._starts: list[int] = []
        self._last = (0, 0)  # the range the previous sample was in: most samples are in it too
        # opened once, while descriptors are plenty, and reread from the start: a check must not
        # need a descriptor when a process has run out of them
        self._maps = os.open("/proc/self/maps", os.O_RDONLY | os.O_CLOEXEC)
        self._lock = threading.Lock()

    def refresh(self) -> list[tuple[int, int]]:
        """The data segments' ranges, sorted by address (read again from the kernel)."""
        chunks = []
        with self._lock:
            os.lseek(self._maps, 0, os.SEEK_SET)
            while chunk := os.read(self._maps, 1 << 16):
                chunks.append(chunk)
        ranges = []
        marker = f"/dev/shm/{file_prefix()}".encode()
        for line in b"".join(chunks).split(b"\n"):
            if marker in line:
                low, _, rest = line.partition(b"-")
                ranges.append((int(low, 16), int(rest.split(b" ", 1)[0], 16)))
        ranges.sort()
        self.ranges = ranges
        self._starts = [low for low, _high in ranges]
        return ranges

    def holds(self, address: int, size: int) -> bool:
        """Whether ``size`` bytes at ``address`` lie inside one mapped data segment."""
        low, high = self._last
        if low <= address and address + size <= high:
            return True
        for attempt in (0, 1):
            at = bisect.bisect_right(self._starts, address) - 1
            if at >= 0:
                low, high = self.ranges[at]
                if address + size <= high:
                    self._last = (low, high)
                    return True
            if attempt == 0:
                self.refresh()
        return False


MAPPED = MappedSegments()


def leased_memory(address: int, size: int, sample: object, borrowed: list[None]) -> memoryview:
    """A received sample's bytes, read-only; the sample is released when nothing made from them is left."""
    if _Memory is not None:
        return memoryview(_Memory(address, size, sample, borrowed))
    raw = _sized(_LEASE_TYPES, size, (_Leased,), ("borrowed", "sample")).from_address(address)
    raw.sample = sample
    raw.borrowed = borrowed
    borrowed.append(None)
    return memoryview(raw).cast("B").toreadonly()


def slot_memory(address: int, size: int, keepalive: object) -> memoryview:
    """Bytes at ``address`` as a memoryview that keeps ``keepalive`` alive while referenced.

    Everything made from the view (slices, numpy arrays) refers to the object that holds
    ``keepalive``: the sample goes back to iceoryx2 only when all of them are gone.
    """
    if _Memory is not None:
        return memoryview(_Memory(address, size, keepalive, None, False))
    raw = _sized(_SLOT_TYPES, size, (), ("keepalive",)).from_address(address)
    raw.keepalive = keepalive
    return memoryview(raw).cast("B")



class ScratchViews:
    """Views on slots that keep nothing alive, one per slot address, made once and reused.

    For bytes used and dropped within one call while the sample is held elsewhere: a
    publisher filling an inline sample before it sends, a subscriber decoding a type whose
    messages keep no view on their bytes. A view may be longer than asked (made for a
    larger sample in the same slot); only the first ``size`` bytes belong to the sample.
    """

    __slots__ = ("_readonly", "_views")

    def __init__(self, readonly: bool = False) -> None:
        self._readonly = readonly
        self._views: dict[int, memoryview] = {}

    def at(self, address: int, size: int) -> memoryview:
        """At least ``size`` bytes at ``address``."""
        memory = self._views.get(address)
        if memory is None or len(memory) < size:
            if len(self._views) > 1024:  # segments reallocated over and over must not grow this forever
                self._views.clear()
            memory = memoryview((ctypes.c_uint8 * size).from_address(address)).cast("B")
            if self._readonly:
                memory = memory.toreadonly()
            self._views[address] = memory
        return memory

    def clear(self) -> None:
        self._views.clear()
