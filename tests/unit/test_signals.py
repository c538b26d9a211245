"""The main thread's sliced waits: what they return, and that they give the interpreter back."""

from __future__ import annotations

import queue
import threading
import time

import pytest

from hetros._signals import SIGNAL_SLICE, next_item, wait_until_set


def test_next_item_gives_an_item_that_comes_later_than_a_slice() -> None:
    items: queue.Queue[str] = queue.Queue()
    threading.Timer(SIGNAL_SLICE * 1.5, items.put, args=("late",)).start()
    assert next_item(items) == "late"


def test_next_item_runs_out_at_its_timeout_not_at_a_slice() -> None:
    items: queue.Queue[str] = queue.Queue()
    began = time.monotonic()
    with pytest.raises(queue.Empty):
        next_item(items, SIGNAL_SLICE * 2.5)
    assert time.monotonic() - began >= SIGNAL_SLICE * 2.5
    with pytest.raises(queue.Empty):
        next_item(items, 0.0)


def test_wait_until_set_returns_once_the_event_is_set() -> None:
    event = threading.Event()
    threading.Timer(SIGNAL_SLICE * 1.5, event.set).start()
    wait_until_set(event)
    assert event.is_set()
