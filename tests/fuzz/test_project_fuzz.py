"""Project files an adversary might write: every one is refused with file:line, or accepted.

Bounded in count and time: ``FUZZ_CASES`` generated files per strategy (10,000 in all by
default), each loaded and checked in under 5 s, with zero tracebacks.
"""

from __future__ import annotations

import os
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hetros import ProjectError
from hetros.project import check, load_project

FUZZ_CASES = int(os.environ.get("HETROS_FUZZ_CASES", "1500"))
PER_CASE_SECONDS = 5.0
NODES_PY = "def talker(node):\n    pass\n"
BASE = {
    "name": "fuzz",
    "targets": {"a": {"kind": "process"}, "b": {"kind": "thread", "cpus": [0]}},
    "nodes": {
        "talker": {"run": "fuzz_nodes:talker", "target": "a", "publish": {"/chatter": "std_msgs/msg/String"}},
        "listener": {"run": "fuzz_nodes:talker", "target": "b",
                     "subscribe": {"/chatter": {"type": "std_msgs/msg/String", "reliability": "reliable"}}},
    },
    "topics": {"/chatter": {"reliability": "reliable", "history": "keep_all", "depth": 10}},
}
FILE_LINE = re.compile(r"\.yaml:\d+")
SETTINGS = settings(max_examples=FUZZ_CASES, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))

scalars = st.one_of(st.none(), st.booleans(), st.integers(-2**70, 2**70), st.floats(allow_nan=True),
                    st.text(max_size=30), st.sampled_from(["thread", "process", "fpga", "keep_all", "/x",
                                                           "std_msgs/msg/Int32", "m:f", "1GiB", "-1"]))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(st.text(max_size=12), inner, max_size=4)),
                      max_leaves=12)


def _paths(tree: object, prefix: tuple[object, ...] = ()) -> list[tuple[object, ...]]:
    out = [prefix]
    if isinstance(tree, dict):
        for key, value in tree.items():
            out += _paths(value, (*prefix, key))
    elif isinstance(tree, list):
        for index, value in enumerate(tree):
            out += _paths(value, (*prefix, index))
    return out


@st.composite
def mutated_projects(draw: st.DrawFn) -> str:
    """The valid base project with a few values replaced, keys added or removed."""
    import copy

    tree: dict[str, object] = copy.deepcopy(BASE)
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(tree) if p]
        path = draw(st.sampled_from(paths))
        holder: object = tree
        for step in path[:-1]:
            holder = holder[step]  # type: ignore[index]
        action = draw(st.sampled_from(["replace", "delete", "add"]))
        if action == "replace":
            holder[path[-1]] = draw(values)  # type: ignore[index]
        elif action == "delete" and isinstance(holder, dict):
            del holder[path[-1]]
        elif isinstance(holder, dict):
            holder[draw(st.text(max_size=12))] = draw(values)
    return yaml.safe_dump(tree, allow_unicode=True)


@st.composite
def damaged_text(draw: st.DrawFn) -> bytes:
    """The valid base project's text with bytes inserted, deleted or flipped."""
    data = bytearray(yaml.safe_dump(BASE).encode())
    for _ in range(draw(st.integers(1, 6))):
        at = draw(st.integers(0, len(data)))
        action = draw(st.sampled_from(["insert", "delete", "flip"]))
        chunk = draw(st.one_of(st.binary(min_size=1, max_size=4),
                               st.sampled_from([b"&a ", b"*a", b"[", b"]", b"{", b"}", b": ", b"\n  ", b"- ",
                                                b"!!python/object ", b"\t", b"<<: ", b"'", b'"', b"\xff"])))
        if action == "insert":
            data[at:at] = chunk
        elif action == "delete":
            del data[at:at + len(chunk)]
        elif at < len(data):
            data[at] ^= chunk[0]
    return bytes(data)


OUTCOMES = {"refused": 0, "accepted": 0}


def _load_and_check(path: Path) -> None:
    start = time.monotonic()
    try:
        project = load_project(path)
        report = check(project)
    except ProjectError as exc:
        assert FILE_LINE.search(str(exc)), f"a refusal must name file:line:\n{exc}"
        OUTCOMES["refused"] += 1
    else:
        for problem in report.errors:
            assert FILE_LINE.search(problem), f"a refusal must name file:line:\n{problem}"
        OUTCOMES["refused" if report.errors else "accepted"] += 1
    assert time.monotonic() - start < PER_CASE_SECONDS


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fuzz")
    (path / "fuzz_nodes.py").write_text(NODES_PY)
    return path


def _fuzz(folder: Path, strategy: st.SearchStrategy[Any], write: Callable[[Path, Any], object]) -> None:
    """Write each generated case as the project file, then load and check it."""

    @SETTINGS
    @given(strategy)
    def case(value: Any) -> None:
        path = folder / "project.yaml"
        write(path, value)
        _load_and_check(path)

    case()


def _text(path: Path, text: str) -> None:
    path.write_text(text, encoding="utf-8")


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_mutated_projects_are_refused_with_file_and_line(folder: Path) -> None:
    _fuzz(folder, mutated_projects(), _text)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_damaged_project_text_is_refused_with_file_and_line(folder: Path) -> None:
    _fuzz(folder, damaged_text(), Path.write_bytes)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_random_bytes_are_refused_with_file_and_line(folder: Path) -> None:
    _fuzz(folder, st.binary(max_size=300), Path.write_bytes)


@pytest.mark.slow
@pytest.mark.timeout(900)
def test_random_yaml_documents_are_refused_with_file_and_line(folder: Path) -> None:
    _fuzz(folder, values, lambda path, tree: _text(path, yaml.safe_dump(tree, allow_unicode=True)))


def test_report_outcomes() -> None:
    """Prints how the generated cases ended (shown with -s; the closing note's table)."""
    print(f"\nproject fuzz outcomes: {OUTCOMES}")
