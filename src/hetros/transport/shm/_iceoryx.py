"""iceoryx2, imported once with its logging quietened (it prints to stderr otherwise)."""

from __future__ import annotations

import os

os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
import iceoryx2 as iox2

from ..._log import get_logger

iox2.set_log_level(iox2.LogLevel.Error)

log = get_logger("hetros.transport.shm")

# The binding's Python wrappers recheck the payload type on every call (~0.3 µs each). Every
# hetros service carries byte slices, so the hot path calls the methods they wrap, when this
# version of the binding has them (tests/conformance/test_shm_specific.py notices a rename).
loan_slice = getattr(iox2.Publisher, "__loan_slice_uninit", iox2.Publisher.loan_slice_uninit)
assume_init = getattr(iox2.SampleMutUninit, "__assume_init", iox2.SampleMutUninit.assume_init)

__all__ = ["assume_init", "iox2", "loan_slice", "log"]
