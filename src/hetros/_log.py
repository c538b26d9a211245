"""hetros's own loggers, with one rate limit for every line that repeats.

A flood of bad input (refused connections, damaged samples, unreachable peers) must not
become a flood of log lines: a blocked log pipe stalls every thread that logs, and the one
line that matters drowns. Each line, told apart by its logger and its format string, is
logged at most ``BURST`` times per ``PERIOD`` seconds; the first one after a window in which
lines were held back says how many. Node loggers (the user's own lines) are not limited.
"""

from __future__ import annotations

import logging
import threading
import time

BURST = 20
PERIOD = 10.0


class RepeatLimit(logging.Filter):
    """At most ``burst`` records of one (logger, format) per ``period`` seconds."""

    def __init__(self, burst: int = BURST, period: float = PERIOD) -> None:
        super().__init__()
        self.burst = burst
        self.period = period
        self._lock = threading.Lock()
        self._windows: dict[tuple[str, str], list[float]] = {}  # key -> [window start, logged, held back]

    def filter(self, record: logging.LogRecord) -> bool:
        key = (record.name, str(record.msg))
        now = time.monotonic()
        with self._lock:
            window = self._windows.get(key)
            held = 0
            if window is None or now - window[0] > self.period:
                held = int(window[2]) if window is not None else 0
                if len(self._windows) > 4096:  # many distinct lines: forget the old windows
                    self._windows.clear()
                window = self._windows[key] = [now, 0.0, 0.0]
            if window[1] >= self.burst:
                window[2] += 1
                return False
            window[1] += 1
        if held:
            record.msg = f"{record.msg} [{held} more like this in the {self.period:g} s before were not logged]"
        return True


_LIMIT = RepeatLimit()


def get_logger(name: str) -> logging.Logger:
    """The logger ``name`` (a ``hetros.*`` name) with the repeat limit on it."""
    logger = logging.getLogger(name)
    if _LIMIT not in logger.filters:
        logger.addFilter(_LIMIT)
    return logger
