"""The credits file of a service: fill levels for back-pressure, and who to wake."""

from __future__ import annotations

import mmap
import os
import struct
from pathlib import Path

import numpy as np

from ..._errors import MachineError
from ..._process import valid_pid
from ._sample import (
    MAX_EVENT_ID,
    MAX_SUBSCRIBER_SLOTS,
)

_SLOT_WORDS = 4
_WORD = struct.Struct("<Q")
_SLOT_TABLE = struct.Struct(f"<{_SLOT_WORDS * MAX_SUBSCRIBER_SLOTS}Q")
_SLOT = struct.Struct(f"<{_SLOT_WORDS}Q")
_VERSION_MASK = (1 << 63) - 1


class Credits:
    """The credits file of one service.

    Layout (little endian u64): ``published`` sequence number, ``waiting`` (a publisher is
    blocked on a full FIFO, so takers must signal), ``version`` (bumped by every subscriber
    that joins or leaves, so the publisher rereads the slots only then), ``back_event`` (the
    publisher's event id on its process' back channel), ``publisher_pid`` (so a subscriber
    that misses messages can tell a publishing process that ended from a lost connection, and
    whether an ``automatic`` publisher is alive), ``asserted_ns`` (CLOCK_MONOTONIC of the
    publisher's last liveliness assertion, for ``manual_by_topic``);
    then per subscriber slot: taken, pid,
    wake channel key, event id. Each word has one writer: the publishing process writes the
    head (but ``version``), a subscriber writes its own slot and bumps ``version``.
    """

    HEAD = 6
    SLOT_WORDS = _SLOT_WORDS
    SIZE = 8 * (HEAD + _SLOT_WORDS * MAX_SUBSCRIBER_SLOTS)

    def __init__(self, path: Path) -> None:
        self.path = path
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o600)
        try:
            if os.fstat(fd).st_size < self.SIZE:
                try:  # backed now: a page the tmpfs cannot back would be a SIGBUS at the first write
                    os.posix_fallocate(fd, 0, self.SIZE)
                except OSError as exc:
                    raise MachineError(f"cannot reserve the {self.SIZE}-byte credits file {path}: {exc.strerror}; "
                                       f"free some of {path.parent} (`df -h {path.parent}`)") from exc
            self._map = mmap.mmap(fd, self.SIZE)
        finally:
            os.close(fd)
        self.words = np.frombuffer(self._map, dtype="<u8")
        self.slots = self.words[self.HEAD:].reshape(MAX_SUBSCRIBER_SLOTS, _SLOT_WORDS)
        # the publisher's copy of the slots it last read whole (slot -> pid, wake key, event id): a slot
        # another process damaged is written back from it, so its subscriber is still woken
        self._known: dict[int, tuple[int, int, int]] = {}
        self.restored = 0  # slots written back from that copy

    # the hot words go through struct on the mapping: a numpy element access costs ~3x more
    @property
    def published(self) -> int:
        value: int = _WORD.unpack_from(self._map, 0)[0]
        return value

    def publish(self, seq: int) -> int:
        """Record ``seq`` as published; returns ``version`` (so the publisher notices joins and leaves)."""
        _WORD.pack_into(self._map, 0, seq)
        return self.version

    @property
    def waiting(self) -> bool:
        return bool(_WORD.unpack_from(self._map, 8)[0])

    @waiting.setter
    def waiting(self, flag: bool) -> None:
        _WORD.pack_into(self._map, 8, int(flag))

    @property
    def version(self) -> int:
        """The count of joins and leaves, kept below 2**63 (the compiled path holds it as a signed
        word); a damaged value is folded back into range and written so."""
        value: int = _WORD.unpack_from(self._map, 16)[0]
        if value > _VERSION_MASK:
            value &= _VERSION_MASK
            _WORD.pack_into(self._map, 16, value)
        return value

    def _bump_version(self) -> None:
        self.words[2] = (int(self.words[2]) + 1) & _VERSION_MASK

    @property
    def back_event(self) -> int:
        """The publisher's event id on its back channel; 0 (none) when the word is not a valid id."""
        event = int(self.words[3])
        return event if 0 < event <= MAX_EVENT_ID else 0

    @back_event.setter
    def back_event(self, event: int) -> None:
        self.words[3] = event

    @property
    def publisher_pid(self) -> int:
        return int(self.words[4])

    @publisher_pid.setter
    def publisher_pid(self, pid: int) -> None:
        self.words[4] = pid

    @property
    def asserted_ns(self) -> int:
        return int(self.words[5])

    @asserted_ns.setter
    def asserted_ns(self, when: int) -> None:
        self.words[5] = when

    def slot(self, index: int) -> tuple[int, int]:
        taken, pid, _key, _event = self.slots[index]
        return int(taken), int(pid)

    def join(self, index: int, taken: int, wake_key: int, event: int) -> None:
        self.slots[index] = (taken, os.getpid(), wake_key, event)
        self._bump_version()

    def leave(self, index: int) -> None:
        self.slots[index] = (0, 0, 0, 0)
        self._bump_version()

    def set_taken(self, index: int, taken: int) -> bool:
        """Record that subscriber ``index`` took up to ``taken``; returns ``waiting``."""
        _WORD.pack_into(self._map, 8 * (self.HEAD + _SLOT_WORDS * index), taken)
        return bool(_WORD.unpack_from(self._map, 8)[0])

    def subscribers(self, published: int | None = None) -> list[tuple[int, int]]:
        """(wake channel key, event id) of every live subscriber slot (read by the publisher).

        Any process of this user can write the file: a slot whose pid, key or event id is out
        of range is written back from the publisher's copy of it, its taken count set to
        ``published`` (its subscriber writes the truth at its next take), or skipped when the
        publisher never saw it whole (its subscriber rewrites it when it next finds nothing to take).
        """
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        found = []
        for index in range(MAX_SUBSCRIBER_SLOTS):
            i = index * _SLOT_WORDS
            pid, key, event = words[i + 1], words[i + 2], words[i + 3]
            if self.valid_slot(pid, key, event):
                self._known[index] = (pid, key, event)
                found.append((key, event))
            elif pid == key == event == 0:
                self._known.pop(index, None)  # left
            elif (known := self._known.get(index)) is not None:
                taken = words[i] if published is None or words[i] <= published else published
                _SLOT.pack_into(self._map, 8 * (self.HEAD + i), taken, *known)
                self.restored += 1
                found.append(known[1:])
        return found

    @staticmethod
    def valid_slot(pid: int, key: int, event: int) -> bool:
        return valid_pid(pid) and 0 < key < 1 << 63 and 0 < event <= MAX_EVENT_ID

    def holds(self, index: int, wake_key: int, event: int) -> bool:
        """Whether slot ``index`` still says what this process' subscriber wrote when it joined."""
        _taken, pid, key, got = _SLOT.unpack_from(self._map, 8 * (self.HEAD + _SLOT_WORDS * index))
        return bool(pid == os.getpid() and key == wake_key and got == event)

    def rejoin(self, index: int, wake_key: int, event: int) -> None:
        """Write this subscriber's identity into its slot again, keeping what it has taken."""
        self.slots[index, 1:] = (os.getpid(), wake_key, event)
        self._bump_version()

    def max_fill(self, published: int) -> int:
        """The fullest live subscriber FIFO, in messages (0 without subscribers); a count past what was
        published reads as empty (``repair`` sets such words right)."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return max((max(0, published - words[i]) for i in range(0, len(words), _SLOT_WORDS) if words[i + 1]),
                   default=0)

    def behind(self, published: int) -> list[tuple[int, int, int]]:
        """(slot, pid, messages not taken yet) of every live subscriber that has not taken all
        of ``published``."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return [(i // _SLOT_WORDS, words[i + 1], published - words[i]) for i in range(0, len(words), _SLOT_WORDS)
                if words[i + 1] and words[i] < published]

    def repair(self, published: int, most: int) -> int:
        """Set right the slots no subscriber could have written: a pid, key or event that is out of range
        (written back from the publisher's copy, else let go: its subscriber rejoins when it next finds
        nothing to take), or a taken count past
        ``published`` or more than ``most`` behind it, which no FIFO holds (it is set to ``published``;
        the subscriber writes the truth at its next take). The count of slots repaired."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        repaired = 0
        for i in range(0, len(words), _SLOT_WORDS):
            taken, pid = words[i], words[i + 1]
            if not pid:
                continue
            index = i // _SLOT_WORDS
            if not self.valid_slot(pid, words[i + 2], words[i + 3]):
                known = self._known.get(index)
                if known is not None:
                    _SLOT.pack_into(self._map, 8 * (self.HEAD + i), published, *known)
                    self.restored += 1
                else:
                    self.leave(index)
                repaired += 1
            elif taken > published or published - taken > most:
                _WORD.pack_into(self._map, 8 * (self.HEAD + i), published)
                repaired += 1
        return repaired

    def full_slots(self, published: int, depth: int) -> list[int]:
        """Slots of live subscribers whose FIFO holds ``depth`` messages already."""
        words = _SLOT_TABLE.unpack_from(self._map, 8 * self.HEAD)
        return [i // _SLOT_WORDS for i in range(0, len(words), _SLOT_WORDS)
                if words[i + 1] and words[i] + depth <= published]

    def close(self) -> None:
        del self.words, self.slots
        try:
            self._map.close()
        except BufferError:
            pass


