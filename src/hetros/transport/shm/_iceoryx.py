"""iceoryx2, imported once with its logging quietened (it prints to stderr otherwise)."""

from __future__ import annotations

import logging
import os

os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
import iceoryx2 as iox2

iox2.set_log_level(iox2.LogLevel.Error)

log = logging.getLogger("hetros.transport.shm")

__all__ = ["iox2", "log"]
