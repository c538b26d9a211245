"""The compiled codec (C) against the generated Python codec it stands in for.

Both must give the same bytes, the same messages and the same errors: the compiled one
hands every case it does not take (odd values, damaged bytes) to the Python one.
"""

from __future__ import annotations

import os
import random
import shutil
import struct
import subprocess
import sys

import numpy as np
import pytest

from hetros import FieldValueError, SerializationError
from hetros.msg import TypeRegistry, _compiled
from hetros.msg._cdr import CdrCodec, Ros1Codec
from tests.support.messages import random_message

COMPILED = TypeRegistry()
MESSAGE_TYPES = [name for name in COMPILED.names() if "/msg/" in name or "/srv/" in name or "/action/" in name]

needs_extension = pytest.mark.skipif(not _compiled.available(), reason="the compiled codec is not built here")


@pytest.fixture(scope="module")
def pure() -> TypeRegistry:
    """A registry whose codecs and validators are the generated Python ones (as with HETROS_PURE_PYTHON=1)."""
    return TypeRegistry(compiled=False)


def _encoded(size: object, encode: object, message: object, at: int = 0) -> bytes:
    length = size(message)  # type: ignore[operator]
    buffer = memoryview(bytearray(b"\xee" * (at + length)))  # stale bytes must not leak into padding
    assert encode(message, buffer, at) == at + length  # type: ignore[operator]
    return bytes(buffer[at:])


def test_the_extension_is_built_wherever_a_compiler_is() -> None:
    """`pip install` builds it when it can; a broken build must not pass silently as the fallback."""
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler on this machine: the pure-Python codecs serve")
    assert _compiled._ccdr is not None, "the C compiler is there, but hetros.msg._ccdr was not built"
    from hetros.transport.shm import _cslot  # type: ignore[attr-defined]  # raises when it was not built

    assert _cslot.Memory is not None
    from hetros.transport.shm import _hotpath

    if not os.environ.get("HETROS_PURE_PYTHON"):
        assert _hotpath.send_cdr is not None and _hotpath.take_cdr is not None, "built, but not in use"
        assert _compiled.ARRAY_HEAD_READ, "numpy's array head differs from what _ccdr.c reads: attributes serve"
        from hetros.transport.shm._endpoints import _Port
        from hetros.transport.shm._service import Service

        # the state the hot path reads and writes per message is in slots it reaches in place
        assert (_cslot.bind_slots(Service), _cslot.bind_slots(_Port)) == (8, 4)


def test_pure_python_is_chosen_by_the_environment() -> None:
    script = ("from hetros.msg import registry; c = registry().codec('sensor_msgs/msg/Image'); "
              "print(c.compiled, c.generated)")
    for flag, expected in (("1", "False True"), ("0", f"{_compiled._ccdr is not None} True")):
        out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, check=True,
                             env={"HETROS_PURE_PYTHON": flag, "PATH": ""})
        assert out.stdout.split() == expected.split()


@needs_extension
@pytest.mark.parametrize("typename", MESSAGE_TYPES)
def test_compiled_codec_matches_the_generated_one(typename: str, pure: TypeRegistry) -> None:
    fast, slow = COMPILED.codec(typename), pure.codec(typename)
    assert slow.generated and not slow.compiled
    assert fast.compiled, f"{typename} is not compiled"
    rnd = random.Random(typename)
    for round_ in range(10):
        message = random_message(COMPILED, typename, rnd)
        at = 8 * (round_ % 3)
        data = _encoded(slow.size, slow.encode, message, at)
        assert _encoded(fast.size, fast.encode, message, at) == data
        assert _encoded(fast.size_lean, fast.encode_lean, message, at) == \
            _encoded(slow.size_lean, slow.encode_lean, message, at)
        buffer = memoryview(bytes(at) + data)
        decoded = fast.decode(buffer, at, len(buffer))
        assert decoded == slow.decode(buffer, at, len(buffer)) == message
        # two registries, two sets of classes: the same frozen class by name, and this registry's
        assert type(decoded).__name__ == type(slow.decode(buffer, at)).__name__
        assert decoded.is_frozen and type(decoded) is COMPILED.get(typename)._frozen_class
        _assert_read_only(decoded)


def _assert_read_only(value: object) -> None:
    if isinstance(value, np.ndarray):
        assert not value.flags.writeable
    elif isinstance(value, list):
        with pytest.raises(Exception, match="handed over"):
            value.append(1)
        for item in value:
            _assert_read_only(item)
    elif hasattr(value, "__fieldnames__"):
        for name in value.__fieldnames__:
            _assert_read_only(getattr(value, name))


@needs_extension
@pytest.mark.parametrize("typename", [n for n in MESSAGE_TYPES if COMPILED.ros1_codec(n) is not None])
def test_compiled_ros1_codec_matches_the_generated_one(typename: str, pure: TypeRegistry) -> None:
    fast, slow = COMPILED.ros1_codec(typename), pure.ros1_codec(typename)
    assert isinstance(fast, Ros1Codec) and isinstance(slow, Ros1Codec)
    assert fast.compiled and not slow.compiled
    rnd = random.Random(f"ros1 {typename}")
    for _ in range(6):
        message = random_message(COMPILED, typename, rnd)
        data = _encoded(slow.size, slow.encode, message)
        assert _encoded(fast.size, fast.encode, message) == data
        assert fast.decode(memoryview(data)) == slow.decode(memoryview(data)) == message


@needs_extension
@pytest.mark.parametrize("typename", ["sensor_msgs/msg/Image", "sensor_msgs/msg/JointState",
                                      "std_msgs/msg/UInt8MultiArray", "sensor_msgs/msg/CameraInfo",
                                      "geometry_msgs/msg/PoseWithCovarianceStamped"])
def test_damaged_bytes_give_the_generated_codecs_result(typename: str, pure: TypeRegistry) -> None:
    """Truncated, flipped and overwritten bytes: the same message or the same error, word for word."""
    fast, slow = COMPILED.codec(typename), pure.codec(typename)
    rnd = random.Random(f"damage {typename}")
    for _ in range(300):
        data = bytearray(_encoded(slow.size, slow.encode, random_message(COMPILED, typename, rnd)))
        how = rnd.randrange(3)
        if how == 0:
            data = data[:rnd.randrange(len(data) + 1)]
        elif data:
            at = rnd.randrange(len(data))
            if how == 1:
                data[at] ^= 1 << rnd.randrange(8)
            else:
                data[at:at + 4] = struct.pack("<I", rnd.choice([0, 1, 3, 2**31, 2**32 - 1, rnd.randrange(64)]))
        outcomes: list[object] = []
        for codec in (fast, slow):
            try:
                decoded = codec.decode(memoryview(bytes(data)))
            except SerializationError as exc:
                outcomes.append(str(exc))
            else:  # compared as bytes: a flipped bit can make a NaN, which equals nothing
                outcomes.append((type(decoded).__name__, _encoded(slow.size, slow.encode, decoded)))
        assert outcomes[0] == outcomes[1]


@needs_extension
def test_values_the_interpreter_refuses_take_the_generated_path(pure: TypeRegistry) -> None:
    """numpy scalars, out-of-range numbers and wrong types: the Python codec's result or error."""
    Image = COMPILED.get("sensor_msgs/msg/Image")
    fast, slow = COMPILED.codec("sensor_msgs/msg/Image"), pure.codec("sensor_msgs/msg/Image")
    for accepted in (Image(height=np.uint32(7), width=np.int64(5)), Image(data=np.arange(3, dtype=np.int8))):
        assert _encoded(fast.size, fast.encode, accepted) == _encoded(slow.size, slow.encode, accepted)
    for bad in (Image(height=2**32), Image(height=-1), Image(encoding=b"rgb8")):
        errors = []
        for codec in (fast, slow):
            with pytest.raises(Exception) as caught:  # whichever the generated code raises
                _encoded(codec.size, codec.encode, bad)
            errors.append((type(caught.value), str(caught.value)))
        assert errors[0] == errors[1]
    with pytest.raises(FieldValueError, match="height"):
        Image._hetros_validate(Image(height=2**32), "Image")


@needs_extension
def test_an_encode_that_does_not_fit_its_buffer_raises_as_before(pure: TypeRegistry) -> None:
    """The shared-memory loan encodes its small part into a bounded room and relies on the raise."""
    String = COMPILED.get("std_msgs/msg/String")
    for codec in (COMPILED.codec("std_msgs/msg/String"), pure.codec("std_msgs/msg/String")):
        assert isinstance(codec, CdrCodec)
        with pytest.raises((struct.error, ValueError, IndexError)):
            codec.encode(String(data="x" * 40), memoryview(bytearray(16)), 0)


def _odd_values(rnd: random.Random) -> object:
    """Values a field may be given that the compiled validator leaves to the generated one."""
    return rnd.choice([-1, 2**32, 2**64, 1.5, "x", b"x", None, True, np.int16(3), np.float32(2.5), 3e39,
                       [1, 2], (1,), np.zeros(2, np.int8), np.zeros(3, np.float64), np.zeros((2, 2), np.uint8)])


@needs_extension
@pytest.mark.parametrize("typename", MESSAGE_TYPES)
def test_compiled_validator_agrees_with_the_generated_one(typename: str, pure: TypeRegistry) -> None:
    """Random messages pass both; with one field set to an odd value, both give the same outcome."""
    fast_cls, slow_cls = COMPILED.get(typename), pure.get(typename)
    rnd = random.Random(f"validate {typename}")
    short = typename.rsplit("/", 1)[-1]
    for _ in range(6):
        message = random_message(COMPILED, typename, rnd)
        fast_cls._hetros_validate(message, short)
        if not message.__fieldnames__:
            continue
        name = rnd.choice(message.__fieldnames__)
        value = _odd_values(rnd)
        outcomes: list[object] = []
        for cls, types in ((fast_cls, COMPILED), (slow_cls, pure)):
            odd = random_message(types, typename, random.Random(0))
            setattr(odd, name, value)
            try:
                cls._hetros_validate(odd, short)
            except FieldValueError as exc:
                outcomes.append(str(exc))
            else:  # accepted, perhaps converted: what the field holds now
                held = getattr(odd, name)
                outcomes.append(repr(held) if not isinstance(held, np.ndarray) else (held.dtype, held.tolist()))
        assert outcomes[0] == outcomes[1], name
    assert "Codec" in repr(fast_cls._hetros_validate) and "Codec" not in repr(slow_cls._hetros_validate)


def _ownership(value: object) -> object:
    """What sealing decided about a message: classes, list types, and per array its flag and identity."""
    if isinstance(value, np.ndarray):
        return ("array", value.flags.writeable, id(value), value.tolist())
    if isinstance(value, list):
        return (type(value).__name__, [_ownership(item) for item in value])
    if hasattr(value, "__fieldnames__"):
        return (type(value).__name__, [_ownership(getattr(value, name)) for name in value.__fieldnames__])
    return value


@needs_extension
@pytest.mark.parametrize("typename", MESSAGE_TYPES)
@pytest.mark.parametrize("callers", [0, 1, 2], ids=["freeze", "copy", "keep"])
def test_compiled_sealer_agrees_with_the_generated_one(typename: str, callers: int, pure: TypeRegistry) -> None:
    """Writable, read-only and loaned arrays, lists and nested messages: sealed alike, same objects kept or copied."""
    from hetros.msg import loaned_array

    rnd = random.Random(f"seal {typename}")
    for _ in range(3):
        seed = rnd.random()
        states = []
        for types in (COMPILED, pure):
            message = random_message(types, typename, random.Random(seed))
            arrays = [name for name in message._array_names if isinstance(getattr(message, name), np.ndarray)]
            for index, name in enumerate(arrays):  # one of each kind of array the sealer tells apart
                array = getattr(message, name)
                kind = (index + int(seed * 5)) % 5
                if kind == 1:
                    array.flags.writeable = False
                elif kind in (2, 3):  # a loan, or a view of one (the sealer walks the bases)
                    loaned = loaned_array(array.size, array.dtype)
                    loaned[:] = array
                    setattr(message, name, loaned if kind == 2 else loaned[:])
                elif kind == 4:  # a read-only view of memory the caller can still write
                    view = array[:]
                    view.flags.writeable = False
                    setattr(message, name, view)
            before = {name: id(getattr(message, name)) for name in arrays}
            sealed = type(message)._hetros_seal(message, callers)
            assert sealed is message and message.is_frozen
            states.append((_strip_ids(_ownership(message)),
                           {name: id(getattr(message, name)) == before[name] for name in arrays}))
        assert states[0] == states[1]


def _strip_ids(state: object) -> object:
    if isinstance(state, tuple) and state and state[0] == "array":
        return state[:2] + state[3:]
    if isinstance(state, tuple):
        return tuple(_strip_ids(item) for item in state)
    if isinstance(state, list):
        return [_strip_ids(item) for item in state]
    return state


def _shares_mutable(original: object, copied: object) -> bool:
    """Whether a copy holds any array, list or message object of its original."""
    if isinstance(copied, (np.ndarray, list)) or hasattr(copied, "__fieldnames__"):
        if copied is original:
            return True
    if isinstance(copied, list) and isinstance(original, list):
        return any(_shares_mutable(a, b) for a, b in zip(original, copied, strict=False))
    if hasattr(copied, "__fieldnames__") and hasattr(original, "__fieldnames__"):
        return any(_shares_mutable(getattr(original, n), getattr(copied, n)) for n in copied.__fieldnames__)
    return False


def _copied(message: object) -> object:
    """What a copy holds: ``_ownership`` without identities, or the error copying raised."""
    from hetros.msg import copy

    try:
        result = copy(message)  # type: ignore[arg-type]
    except Exception as exc:  # whichever error it is, both paths must raise the same
        return (type(exc).__name__, str(exc))
    assert not result.is_frozen and not _shares_mutable(message, result)
    return _strip_ids(_ownership(result))


@needs_extension
@pytest.mark.parametrize("typename", MESSAGE_TYPES)
def test_compiled_copier_agrees_with_the_generated_one(typename: str, pure: TypeRegistry) -> None:
    """Fresh, frozen and loaned messages, and ones with an odd value in a field: copied alike, nothing shared."""
    from hetros.msg import freeze, loaned_array

    rnd = random.Random(f"copy {typename}")
    for round_ in range(6):
        seed = rnd.random()
        name = rnd.choice(COMPILED.get(typename).__fieldnames__ or ("",))
        odd = _odd_values(rnd)
        states = []
        for types in (COMPILED, pure):
            message = random_message(types, typename, random.Random(seed))
            arrays = [n for n in message._array_names if isinstance(getattr(message, n), np.ndarray)]
            if arrays and round_ % 3 == 1:
                array = getattr(message, arrays[0])
                loaned = loaned_array(array.size, array.dtype)
                loaned[:] = array
                setattr(message, arrays[0], loaned)
            if round_ % 3 == 2 and name:
                setattr(message, name, odd)
            states.append(_copied(message))
            if round_ % 3 == 0:
                states.append(_copied(freeze(message)))
        assert states[:len(states) // 2] == states[len(states) // 2:]
    assert "Codec" in repr(COMPILED.get(typename)._hetros_copy)


@pytest.mark.parametrize("ros1", [False, True], ids=["cdr", "ros1"])
def test_a_forged_element_count_allocates_nothing_before_it_is_refused(ros1: bool, pure: TypeRegistry) -> None:
    """A 4-byte count of 2**28 messages in an 8-byte body: the compiled decoder made a list of
    that many slots (gigabytes, seconds with the GIL held) before it found the bytes missing."""
    import tracemalloc

    typename = "std_msgs/msg/MultiArrayLayout"  # MultiArrayDimension[] dim, uint32 data_offset
    body = struct.pack("<II", 2**28, 0)
    for registry in (COMPILED, pure):
        codec = registry.ros1_codec(typename) if ros1 else registry.codec(typename)
        tracemalloc.start()
        try:
            with pytest.raises(SerializationError):
                codec.decode(memoryview(body))
            _current, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
        assert peak < 1 << 20, f"decoding a forged count allocated {peak} bytes"
