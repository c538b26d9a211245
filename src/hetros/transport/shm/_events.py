"""Wake-up plumbing: the wake channel of a node, the back channel of a process, descriptor limits."""

from __future__ import annotations

import itertools
import os
import resource
import threading
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any, Generic, TypeVar

from ..._errors import TransportError
from .._base import Wake
from ._iceoryx import iox2, log, sha1
from ._sample import (
    INTERRUPT_EVENT,
    LOSS_GRACE,
    MAX_EVENT_ID,
    MAX_EVENT_PORTS,
)

if TYPE_CHECKING:
    from ._service import Service


def channel_key(session: str, owner: str) -> int:
    """A wake channel's key: 63 bits, never 0 (0 marks an empty slot)."""
    digest = sha1(f"{session}/{owner}".encode()).digest()
    return (int.from_bytes(digest[:8], "little") >> 1) or 1


def event_service(node: Any, name: str, what: str) -> Any:
    try:
        return (node.service_builder(iox2.ServiceName.new(name)).event()
                .max_listeners(MAX_EVENT_PORTS).max_notifiers(MAX_EVENT_PORTS)
                .event_id_max_value(MAX_EVENT_ID).open_or_create())
    except Exception as exc:  # iceoryx2 raises its own exception classes
        raise TransportError(f"cannot open the {what} ({name}): {type(exc).__name__}: {exc}; "
                             f"{fd_hint()}") from exc


def fd_hint() -> str:
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    try:
        used = str(len(os.listdir("/proc/self/fd")))
    except OSError:  # out of descriptors itself, most likely
        used = "all its"
    return (f"this process has {used} files open with a limit of {soft} (hard limit {hard}); "
            "if that is close, raise the limit (ulimit -n) or spread the topics over fewer processes")


def raise_open_file_limit() -> tuple[int, int]:
    """Raise the soft open-file limit to the hard one: each endpoint holds a few descriptors.

    Returns (soft, hard) after the attempt; a hard limit below a few thousand is logged.
    """
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft < hard:
        try:
            resource.setrlimit(resource.RLIMIT_NOFILE, (hard, hard))
            soft = hard
        except (ValueError, OSError):
            pass
    if soft < 4096:
        log.warning("the open-file limit is %d (hard limit %d): shared memory needs about 10 file "
                    "descriptors per topic and process, so large graphs may not start; raise it "
                    "with `ulimit -n`", soft, hard)
    return soft, hard


T = TypeVar("T")


class EventRoutes(Generic[T]):
    """Event ids within iceoryx2's bound (1..MAX_EVENT_ID; 0 is the interrupt), each naming its targets.

    Ids wrap past the bound, so one id may name several targets: a spurious wake-up of
    the others costs one empty check, an id out of bounds would be an iceoryx2 error.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._routes: dict[int, list[T]] = {}
        self._ids = itertools.count(0)

    def add(self, target: T) -> int:
        with self._lock:
            event = next(self._ids) % MAX_EVENT_ID + 1
            self._routes.setdefault(event, []).append(target)
            return event

    def remove(self, event: int, target: T) -> None:
        with self._lock:
            targets = self._routes.get(event, [])
            if target in targets:
                targets.remove(target)

    def targets(self, events: Iterable[int]) -> list[T]:
        with self._lock:
            return [target for event in events for target in self._routes.get(event, ())]


class WakeChannel:
    """Where the readers of one node signal that data may be there: one wait covers them all.

    Publishers notify it with the reader's event id; the node's executor waits on it and
    calls the wake function registered for each id that fired. Event id 0 is the executor's
    own interrupt (an in-process notification or shutdown).
    """

    def __init__(self, node: Any, session: str, owner: str) -> None:
        self.owner = owner
        self.key = channel_key(session, owner)
        self._service = event_service(node, wake_channel_name(session, self.key),
                                       f"wake channel of node {owner!r}")
        self._listener = self._service.listener_builder().create()
        self._interrupter = self._service.notifier_builder().create()
        self._routes: EventRoutes[Wake] = EventRoutes()
        self._pollers: list[tuple[Callable[[], bool], Wake]] = []
        self._suspects: set[int] = set()
        self._lock = threading.Lock()

    def register(self, wake: Wake, pending: Callable[[], bool]) -> int:
        """An event id for one reader; ``wake`` runs (in the waiting thread) when it fires,
        or when a ``poll`` finds ``pending()`` true."""
        with self._lock:
            self._pollers = [*self._pollers, (pending, wake)]
        return self._routes.add(wake)

    def unregister(self, event: int, wake: Wake) -> None:
        self._routes.remove(event, wake)
        with self._lock:
            self._suspects.discard(event)
            self._pollers = [(p, w) for p, w in self._pollers if w is not wake]

    def poll(self) -> None:
        """Run the wake of every reader with data now (no system call: the spin of a hot node)."""
        for pending, wake in self._pollers:
            if pending():
                wake()

    def suspect(self, event: int, suspicious: bool) -> None:
        """A reader saw published samples it could not receive: wake it again soon to recheck."""
        with self._lock:
            if suspicious:
                self._suspects.add(event)
            else:
                self._suspects.discard(event)

    def interrupt(self) -> None:
        self._interrupter.notify_with_custom_event_id(_INTERRUPT)

    def wait(self, timeout: float | None) -> None:
        """Block (without the GIL) until an event or ``timeout``; run the wake of each reader that fired."""
        if self._suspects:
            timeout = LOSS_GRACE if timeout is None else min(timeout, LOSS_GRACE)
        try:
            if timeout is None:
                fired = self._listener.blocking_wait()
            else:
                fired = self._listener.timed_wait(iox2.Duration.from_secs_f64(max(timeout, 0.0)))
        except iox2.ListenerWaitError as exc:
            if not interrupted(exc):
                raise TransportError(f"waiting on the wake channel of node {self.owner!r} failed: {exc}") from exc
            fired = []  # a signal (SIGCONT after SIGSTOP, a debugger): the caller rechecks and waits again
        events = {activation.id.as_value for activation in fired}
        with self._lock:
            events |= self._suspects
        for wake in self._routes.targets(events):
            wake()

    def close(self) -> None:
        self._pollers = []
        self._listener = self._interrupter = self._service = None


_INTERRUPT = iox2.EventId.new(INTERRUPT_EVENT)


def interrupted(exc: Exception) -> bool:
    """Whether an iceoryx2 wait ended because a signal came (EINTR): retried, never an error."""
    return "Interrupt" in str(exc) or "Interrupt" in type(exc).__name__


def wake_channel_name(session: str, key: int) -> str:
    return f"hetros/{session}/wake/{key:016x}"


def back_channel_name(session: str, process: str) -> str:
    digest = sha1(process.encode()).hexdigest()[:20]
    return f"hetros/{session}/back/{digest}"


class BackChannel:
    """The publishing process' one back channel and the one thread that watches it.

    Subscribers notify it (with the service's event id) after taking from a FIFO a blocked
    publisher waits on, and when they join; the thread wakes the blocked publisher and
    connects a late joiner so that it receives the history.
    """

    def __init__(self, node: Any, session: str, process: str) -> None:
        self._service = event_service(node, back_channel_name(session, process), f"back channel of {process!r}")
        self._listener = self._service.listener_builder().create()
        self._interrupter = self._service.notifier_builder().create()
        self._services: EventRoutes[Service] = EventRoutes()
        self._closed = False
        self._thread = threading.Thread(target=self._watch, name="hetros-shm-back", daemon=True)
        self._thread.start()

    def register(self, service: Service) -> int:
        return self._services.add(service)

    def _watch(self) -> None:
        while not self._closed:
            try:
                fired = self._listener.blocking_wait()
            except iox2.ListenerWaitError as exc:
                if interrupted(exc):
                    continue
                log.error("the back channel of this process failed (%s): blocked publishers now recheck "
                          "their subscribers every 10 ms instead of being woken", exc)
                return
            for service in self._services.targets({activation.id.as_value for activation in fired}):
                service.subscriber_moved()

    def close(self) -> None:
        self._closed = True
        self._interrupter.notify_with_custom_event_id(_INTERRUPT)
        self._thread.join(timeout=2.0)
        self._listener = self._interrupter = self._service = None


