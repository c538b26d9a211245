"""Interface files an adversary might write: each is refused with file:line, or it works.

"Works" means the generated class constructs with its defaults and round-trips through
CDR. Bounded: ``FUZZ_CASES`` cases per strategy (10,000 in all by default), each under 5 s.
"""

from __future__ import annotations

import itertools
import os
import random
import re
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hetros import DefinitionError
from hetros.msg import TypeRegistry
from tests.support.messages import random_message

FUZZ_CASES = int(os.environ.get("HETROS_FUZZ_CASES", "1500"))
SETTINGS = settings(max_examples=FUZZ_CASES, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))
FILE_LINE = re.compile(r"\.(msg|srv|action):[1-9]\d*: ")

TYPES = ["bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
         "float32", "float64", "string", "wstring", "time", "duration", "string<=5", "Header",
         "std_msgs/String", "geometry_msgs/msg/Point", "Other", "Self", "Missing", "1Bad", "in$t", "int32<=3"]
SUFFIXES = ["", "", "", "[]", "[3]", "[<=4]", "[<=]", "[x]", "[-1]"]
NAMES = ["x", "data", "self", "np", "copy", "class", "a_b", "a__b", "a_", "X", "9lives", "ok1", "é", "__init__"]
CONSTANTS = ["C", "MAX", "A_B", "lower", "A__B"]
VALUES = ["0", "5", "-1", "300", "2**40", "abc", "true", "false", "1.5", "'quoted'", '"dq"', "[1, 2, 3]", "[]",
          "[1, 'a']", "x y z", "1 2", "", "0x10", "nan", "1e400", "# comment"]


@st.composite
def definition_line(draw: st.DrawFn) -> str:
    kind = draw(st.sampled_from(["field", "field", "default", "constant", "comment", "junk", "blank"]))
    typ = draw(st.sampled_from(TYPES)) + draw(st.sampled_from(SUFFIXES))
    if kind == "field":
        return f"{typ} {draw(st.sampled_from(NAMES))}"
    if kind == "default":
        return f"{typ} {draw(st.sampled_from(NAMES))} {draw(st.sampled_from(VALUES))}"
    if kind == "constant":
        return f"{typ} {draw(st.sampled_from(CONSTANTS))}={draw(st.sampled_from(VALUES))}"
    if kind == "comment":
        return "# " + draw(st.text(max_size=20))
    if kind == "junk":
        return draw(st.text(max_size=30))
    return ""


@st.composite
def package_files(draw: st.DrawFn) -> dict[str, bytes]:
    """One to three interface files made of plausible and implausible lines."""
    files: dict[str, bytes] = {}
    for _ in range(draw(st.integers(1, 3))):
        folder, suffix, parts = draw(st.sampled_from([("msg", "msg", 1), ("srv", "srv", 2), ("action", "action", 3)]))
        stem = draw(st.sampled_from(["Self", "Other", "Thing", "1Foo", "class", "Two_Parts", "ok"]))
        sections = draw(st.integers(1, 4)) if draw(st.booleans()) else parts
        body = "\n---\n".join("\n".join(draw(st.lists(definition_line(), max_size=5))) for _ in range(sections))
        data = body.encode()
        if draw(st.integers(0, 9)) == 0:
            data += draw(st.binary(max_size=8))
        files[f"{folder}/{stem}.{suffix}"] = data
    return files


_counter = itertools.count()


OUTCOMES = {"refused": 0, "accepted": 0}


def _load(root: Path, types: TypeRegistry, files: dict[str, bytes]) -> None:
    package = _write(root, files)
    start = time.monotonic()
    try:
        types.load_folder(package)
    except DefinitionError as exc:
        if "no msg/*.msg, srv/*.srv" not in str(exc):
            assert FILE_LINE.search(str(exc)), f"a refusal must name file:line:\n{exc}"
        OUTCOMES["refused"] += 1
    else:
        OUTCOMES["accepted"] += 1
        for name in types.names():
            if name.startswith(package.name + "/"):
                cls = types.get(name)
                message = cls()
                assert types.deserialize(types.serialize(message), name) == message
                _cross_check_codec(types, name)
    assert time.monotonic() - start < 5.0


def _cross_check_codec(types: TypeRegistry, name: str) -> None:
    """The generated codec of a fuzzed type writes and reads rosbags' bytes."""
    codec = types.codec(name)
    if not codec.generated:
        return
    message = random_message(types, name, random.Random(name))
    reference = bytes(types.serialize(message))[4:]
    buffer = bytearray(codec.size(message))
    assert codec.encode(message, memoryview(buffer)) == len(reference)
    assert bytes(buffer) == reference
    assert codec.decode(memoryview(reference)) == message


@pytest.fixture(scope="module")
def types() -> TypeRegistry:
    return TypeRegistry()


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_generated_definitions_are_refused_with_file_and_line_or_work(tmp_path: Path, types: TypeRegistry) -> None:
    @SETTINGS
    @given(package_files())
    def case(files: dict[str, bytes]) -> None:
        _load(tmp_path, types, files)

    case()


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_random_text_definitions_are_refused_with_file_and_line_or_work(tmp_path: Path,
                                                                        types: TypeRegistry) -> None:
    @SETTINGS
    @given(st.sampled_from(["msg/Rand.msg", "srv/Rand.srv", "action/Rand.action"]), st.binary(max_size=200))
    def case(rel: str, data: bytes) -> None:
        _load(tmp_path, types, {rel: data})

    case()


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_recursive_definitions_are_refused(tmp_path: Path, types: TypeRegistry) -> None:
    @SETTINGS
    @given(st.integers(1, 30), st.sampled_from(["", "[]", "[2]", "[<=3]"]))
    def case(length: int, suffix: str) -> None:
        files = {f"msg/T{i}.msg": f"int32 x\nT{(i + 1) % length}{suffix} next\n".encode() for i in range(length)}
        with pytest.raises(DefinitionError, match="contain itself"):
            types.load_folder(_write(tmp_path, files))

    case()


def test_report_outcomes() -> None:
    """Prints how the generated cases ended (shown with -s; the closing note's table)."""
    print(f"\n.msg fuzz outcomes: {OUTCOMES}")


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_damaged_standard_definitions_are_refused_or_work(tmp_path: Path, types: TypeRegistry) -> None:
    base = b"# pose\nstd_msgs/Header header\nfloat64[9] covariance [0,0,0,0,0,0,0,0,0]\nint32 X=5\nstring name 'a'\n"

    @SETTINGS
    @given(st.lists(st.tuples(st.integers(0, len(base)), st.binary(min_size=0, max_size=3)), min_size=1, max_size=4))
    def case(edits: list[tuple[int, bytes]]) -> None:
        data = bytearray(base)
        for at, chunk in edits:
            data[at:at + len(chunk)] = chunk[::-1] if chunk else b""
        _load(tmp_path, types, {"msg/Pose.msg": bytes(data)})

    case()


def _write(root: Path, files: dict[str, bytes]) -> Path:
    package = root / f"fuzz_pkg{next(_counter)}"
    for rel, data in files.items():
        path = package / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    return package


WIRE_TYPES = ["sensor_msgs/msg/Image", "sensor_msgs/msg/PointCloud2", "diagnostic_msgs/msg/DiagnosticArray",
              "std_msgs/msg/Float64MultiArray", "geometry_msgs/msg/PoseWithCovarianceStamped"]


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_damaged_wire_bytes_get_a_serialization_error_or_decode(types: TypeRegistry) -> None:
    """Whatever the bytes, the generated decoder returns a message or raises SerializationError."""
    from hetros import SerializationError

    encoded = {}
    for name in WIRE_TYPES:
        message = random_message(types, name, random.Random(name))
        encoded[name] = bytes(types.serialize(message))[4:]

    @SETTINGS
    @given(st.sampled_from(WIRE_TYPES),
           st.lists(st.tuples(st.integers(0, 400), st.binary(min_size=1, max_size=4)), max_size=4),
           st.integers(0, 600))
    def case(name: str, edits: list[tuple[int, bytes]], cut: int) -> None:
        data = bytearray(encoded[name])
        for at, chunk in edits:
            data[at:at + len(chunk)] = chunk
        data = data[:cut] if cut < len(data) else data
        try:
            types.codec(name).decode(memoryview(bytes(data)))
        except SerializationError:
            pass

    case()
