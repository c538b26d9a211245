"""One thread per participant that waits for data and runs the readers' handlers.

Why not the binding's listeners: Cyclone calls a listener on its receive thread with the
reader's locks held; a Python listener then needs the GIL, while a Python thread holding
the GIL in a take of that reader needs those locks. That deadlock stops the receive thread,
and with it every topic of the process and the leases its peers renew (seen as hosts
"leaving" and "returning" every second). Here Cyclone's threads never run Python: this
thread waits on a waitset without the GIL, then takes, holding no Cyclone lock.
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable
from typing import Any

from cyclonedds.core import DDSException, InstanceState, ReadCondition, SampleState, ViewState, WaitSet
from cyclonedds.util import duration

from ..._log import get_logger

log = get_logger("hetros.dds")

_ANY = SampleState.Any | ViewState.Any | InstanceState.Any
_UNREAD = SampleState.NotRead | ViewState.Any | InstanceState.Any


class Waiter:
    def __init__(self, participant: Any, name: str) -> None:
        self._waitset = WaitSet(participant)
        self._entries: dict[int, tuple[Any, Callable[[], Callable[[], None] | None]]] = {}
        self._lock = threading.Lock()
        self._closed = False
        self._thread = threading.Thread(target=self._run, name=f"dds-wait:{name}", daemon=True)
        self._thread.start()

    def watch(self, reader: Any, handler: Callable[[], None], unread_only: bool = False) -> None:
        """Run ``handler`` (which must take everything waiting) whenever ``reader`` has data, or with
        ``unread_only`` whenever it has samples not read yet (a handler that leaves samples in the
        reader marks them read, so they do not wake this thread again). A bound method is held
        weakly: an endpoint nobody holds stops being watched and is deleted."""
        condition = ReadCondition(reader, _UNREAD if unread_only else _ANY)
        strong: Callable[[], Callable[[], None] | None]
        if hasattr(handler, "__self__"):
            strong = weakref.WeakMethod(handler)
        else:
            strong = lambda: handler
        with self._lock:
            self._entries[condition._ref] = (condition, strong)
        self._waitset.attach(condition)
        self._waitset.set_trigger(True)

    def _run(self) -> None:
        while not self._closed:
            self._waitset.wait(duration(milliseconds=500))  # without the GIL (ctypes)
            if self._closed:
                return
            self._waitset.set_trigger(False)
            with self._lock:
                entries = list(self._entries.items())
            for ref, (condition, get) in entries:
                handler = get()
                if handler is None:
                    self._drop(ref, condition)
                    continue
                try:
                    triggered = condition.triggered
                except DDSException:  # its reader was deleted meanwhile (an endpoint closing)
                    self._drop(ref, condition)
                    continue
                if triggered:
                    try:
                        handler()
                    except Exception:  # a handler's failure must not end every other reader's delivery
                        log.exception("a DDS reader's handler failed")
                del handler

    def _drop(self, ref: int, condition: Any) -> None:
        with self._lock:
            self._entries.pop(ref, None)
        try:
            self._waitset.detach(condition)
        except Exception:
            pass

    def close(self) -> None:
        self._closed = True
        self._waitset.set_trigger(True)
        if self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
