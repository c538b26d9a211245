"""A shared-memory slot as a buffer: the compiled one and the ctypes fallback keep the same promises."""

from __future__ import annotations

import ctypes
import gc
from collections.abc import Iterator

import numpy as np
import pytest

from hetros.transport.shm import _sample


@pytest.fixture(params=["compiled", "ctypes"])
def implementation(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[str]:
    if request.param == "ctypes":
        monkeypatch.setattr(_sample, "_Memory", None)
    elif _sample._Memory is None:
        pytest.skip("the compiled slot buffer is not built here")
    yield request.param


class Sample:
    """Stands in for an iceoryx2 sample: what must stay alive while its bytes are viewed."""

    released = 0

    def __del__(self) -> None:
        Sample.released += 1


def test_a_received_sample_is_read_only_and_held_until_its_last_view_dies(implementation: str) -> None:
    raw = (ctypes.c_uint8 * 64)(*range(64))
    borrowed: list[None] = []
    Sample.released = 0
    memory = _sample.leased_memory(ctypes.addressof(raw), 64, Sample(), borrowed)
    assert memory.readonly and memory.format == "B" and len(memory) == 64
    assert bytes(memory[:4]) == b"\x00\x01\x02\x03" and len(borrowed) == 1
    with pytest.raises(TypeError):
        memory[0] = 1
    array = np.frombuffer(memory, np.uint8, 8, 8)
    assert not array.flags.writeable and array[0] == 8
    del memory
    gc.collect()
    assert len(borrowed) == 1 and Sample.released == 0, "a numpy view still holds the sample"
    del array
    gc.collect()
    assert borrowed == [] and Sample.released == 1


def test_a_slot_being_filled_is_writable_and_keeps_its_sample(implementation: str) -> None:
    raw = (ctypes.c_uint8 * 16)()
    Sample.released = 0
    memory = _sample.slot_memory(ctypes.addressof(raw), 16, Sample())
    assert not memory.readonly
    view = np.frombuffer(memory, np.uint8)
    view[:] = 7
    assert bytes(raw) == b"\x07" * 16
    del memory
    gc.collect()
    assert Sample.released == 0
    del view
    gc.collect()
    assert Sample.released == 1


def test_the_compiled_buffer_refuses_what_it_cannot_hold() -> None:
    if _sample._Memory is None:
        pytest.skip("the compiled slot buffer is not built here")
    with pytest.raises(ValueError, match="address"):
        _sample._Memory(0, 8, None)
    with pytest.raises(TypeError, match="borrowed must be a list"):
        _sample._Memory(16, 8, None, ())
