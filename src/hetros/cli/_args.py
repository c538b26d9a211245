"""The kinds of number a command line takes, each checked where it is parsed.

``float("nan")``, ``1e-320`` and ``-5`` are all floats: a duration, a rate or a count that is
one of them reaches a loop that never ends or a division that overflows. Each kind here says
what it must be, in argparse's own error line (``argument --duration: ...``), before any
command runs.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

# a week: longer than any look, shorter than what overflows a deadline in nanoseconds
MAX_SECONDS = 7 * 24 * 3600.0
MIN_HZ, MAX_HZ = 1e-3, 1e6


def _number(text: str, kind: type[float] | type[int], what: str) -> float:
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{what}, not {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"{what}, not {text!r}")
    return value


def _ranged(kind: type[float] | type[int], low: float, high: float, what: str,
            low_open: bool = False) -> Callable[[str], float]:
    def parse(text: str) -> float:
        value = _number(text, kind, what)
        if value < low or value > high or (low_open and value == low):
            raise argparse.ArgumentTypeError(f"{what}, not {text!r}")
        return value
    parse.__name__ = what
    return parse


seconds = _ranged(float, 0.0, MAX_SECONDS, f"must be seconds from 0 to {MAX_SECONDS:g}")
positive_seconds = _ranged(float, 1e-3, MAX_SECONDS, f"must be seconds from 0.001 to {MAX_SECONDS:g}")
hertz = _ranged(float, MIN_HZ, MAX_HZ, f"must be a rate in Hz from {MIN_HZ:g} to {MAX_HZ:g}")
speed = _ranged(float, 1e-3, 1e3, "must be a speed factor from 0.001 to 1000")
count = _ranged(int, 0, 1_000_000_000, "must be a whole number from 0 to 1000000000")
positive_count = _ranged(int, 1, 1_000_000_000, "must be a whole number from 1 to 1000000000")
port = _ranged(int, 0, 65535, "must be a TCP port from 0 to 65535")
milliseconds = _ranged(float, 0.0, 1e7, "must be milliseconds from 0 to 10000000")
microseconds = _ranged(float, 0.0, 1e9, "must be microseconds from 0 to 1000000000")

__all__ = ["count", "hertz", "microseconds", "milliseconds", "port", "positive_count", "positive_seconds",
           "seconds", "speed"]
