"""One rate limit for every repeated hetros log line; the user's node lines are never limited."""

from __future__ import annotations

import logging
import time

import pytest

from hetros._log import BURST, RepeatLimit, get_logger
from hetros.runtime._log import node_logger


def _record(name: str, msg: str, *args: object) -> logging.LogRecord:
    return logging.LogRecord(name, logging.WARNING, __file__, 1, msg, args, None)


def test_a_repeated_line_passes_burst_times_per_period_then_says_how_many_were_held() -> None:
    limit = RepeatLimit(burst=20, period=0.2)
    passed = [limit.filter(_record("hetros.ros1", "peer %s refused", n)) for n in range(50)]
    assert passed == [True] * 20 + [False] * 30
    assert limit.filter(_record("hetros.ros1", "another line %s", 1)), "other lines have their own budget"
    time.sleep(0.25)
    record = _record("hetros.ros1", "peer %s refused", 51)
    assert limit.filter(record)
    assert record.getMessage() == "peer 51 refused [30 more like this in the 0.2 s before were not logged]"


def test_hetros_loggers_carry_the_limit_and_node_loggers_do_not(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    transport = get_logger("hetros.test_limit")
    for n in range(BURST * 3):
        transport.info("refused request %d", n)
    node = node_logger("talker")
    for n in range(BURST * 3):
        node.info("hello %d", n)
    lines = caplog.text.splitlines()
    assert sum("refused request" in line for line in lines) == BURST
    assert sum("hello" in line for line in lines) == BURST * 3


def test_a_damaged_iceoryx2_node_counter_is_named_with_the_fix() -> None:
    """The counter is machine-wide, so the suite does not damage the real one: the message the
    shm domain raises when iceoryx2 refuses a node id is checked on iceoryx2's error text."""
    from hetros.transport.shm._domain import node_failure

    text = node_failure(Exception("NodeCreationFailure::UnableToGenerateUniqueNodeId"))
    assert "node counter" in text and "global_mgmt" in text and "remove that file" in text
    assert "files open" in node_failure(Exception("InsufficientPermissions"))
