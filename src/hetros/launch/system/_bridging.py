"""What the bridges to ROS 1 and ROS 2 share."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from typing import Any


class Imported:
    """The messages a bridge brought in from the other graph, so a topic both imported and exported
    does not send the other graph's own messages back to it (in a process a subscriber gets the
    very object)."""

    def __init__(self, remembered: int = 256) -> None:
        self._order: deque[Any] = deque()
        self._ids: set[int] = set()
        self._remembered = remembered
        self._lock = threading.Lock()

    def keep(self, publish: Callable[[Any], None]) -> Callable[[Any], None]:
        def imported(message: Any) -> None:
            with self._lock:
                self._order.append(message)  # held, so its id stays its own while remembered
                self._ids.add(id(message))
                if len(self._order) > self._remembered:
                    self._ids.discard(id(self._order.popleft()))
            publish(message)

        return imported

    def skip(self, publish: Callable[[Any], None]) -> Callable[[Any], None]:
        def exported(message: Any) -> None:
            with self._lock:
                if id(message) in self._ids:
                    return
            publish(message)

        return exported
