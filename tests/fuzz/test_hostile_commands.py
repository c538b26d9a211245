"""Every `hetros` command, given the arguments an unlucky user types (nan, 1e-320, -5, 10**30, YAML
that is not the value's kind, paths that are FIFOs, /dev/zero or folders, control characters), and a
launch registry another program has scribbled in: each ends with its answer or one error line, never a
traceback (exit 70, which writes a crash report this suite's run fails on) and never a hang.

The commands run in this process (``hetros.cli.main``) against an empty private runtime folder, so a
look at a launch ends at "no running launch" after its arguments were checked; those that start
servers, launches or long jobs (launch, master, bench, advise, hw, foxglove, record) are given only
``--help`` and bad numbers, which argparse must refuse before anything starts.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import threading
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hetros.cli import EXIT_BUG, build_parser, main
from hetros.launch.launcher._registry import format_launches, registry_folder, running

SOAK = os.environ.get("HETROS_SOAK") == "1"
CASES = int(os.environ.get("HETROS_HOSTILE_CASES", 10_000 if SOAK else 2_000))
SETTINGS = settings(max_examples=CASES, deadline=None, derandomize=True, database=None,
                    suppress_health_check=list(HealthCheck))
# they start something that runs on (a server, a launch, a benchmark, synthesis): their numbers only
STARTERS = {"launch", "master", "bench", "advise", "hw", "foxglove", "record", "play", "graph"}


def _commands(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()) -> dict[tuple[str, ...], Any]:
    """Every leaf command (``("topic", "echo")``) with its parser."""
    found: dict[tuple[str, ...], Any] = {}
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                found.update(_commands(sub, (*prefix, name)))
    return found or {prefix: parser}


COMMANDS = _commands(build_parser())


@pytest.fixture(scope="module")
def hostile_paths(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    folder = tmp_path_factory.mktemp("paths")
    os.mkfifo(folder / "fifo")
    (folder / "garbage.yaml").write_bytes(b"\x00\xff{[&a *a" * 10)
    (folder / "deep.json").write_text("[" * 100_000)
    (folder / "bomb.yaml").write_text("a: &a [x,x,x,x,x,x,x,x,x]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]\n"
                                      "c: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]\nd: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]\n"
                                      "e: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]\nf: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]\n"
                                      "g: [*f,*f,*f,*f,*f,*f,*f,*f,*f]\n")
    return {"fifo": str(folder / "fifo"), "zero": "/dev/zero", "folder": str(folder), "missing": str(folder / "no"),
            "garbage": str(folder / "garbage.yaml"), "deep": str(folder / "deep.json"),
            "bomb": str(folder / "bomb.yaml"), "out": str(folder / "out" / "written.yaml")}


def _words(paths: dict[str, str]) -> st.SearchStrategy[str]:
    numbers = st.sampled_from(["nan", "inf", "-inf", "0", "-5", "1e-320", "1e308", "10" * 20, "0x10", "1.5", "3"])
    values = st.sampled_from(["[1, 2]", "{a: 1}", "{data: hi}", "{", "'", "!!python/object:os.system ls", "~",
                              "*x", "&a [*a]", "/chatter", "chatter", "/", "//x", "std_msgs/msg/String", "a/b/c/d",
                              "std_msgs/String", "x:=y", "\x1b[2J", "é\x00", "-", "--", ""])
    return st.one_of(numbers, values, st.sampled_from(sorted(paths.values())), st.text(max_size=12))


@st.composite
def _command_lines(draw: Any, paths: dict[str, str]) -> list[str]:
    command = draw(st.sampled_from(sorted(COMMANDS)))
    parser = COMMANDS[command]
    options = [a for a in parser._actions if a.option_strings and "-h" not in a.option_strings]
    argv = list(command)
    words = _words(paths)
    for _ in range(draw(st.integers(0, 5))):
        if options and draw(st.booleans()):
            option = draw(st.sampled_from(options))
            argv.append(draw(st.sampled_from(option.option_strings)))
            if option.nargs != 0:
                argv.append(draw(words))
        else:
            argv.append(draw(words))
    if command[0] in STARTERS:  # numbers only: argparse refuses them before anything starts
        numeric = [a for a in options if a.type is not None and a.type not in (str,)]
        if not numeric:
            return [*command, "--help"]
        option = draw(st.sampled_from(numeric))
        return [*command, option.option_strings[0], draw(st.sampled_from(["nan", "-5", "inf", "-inf", "x", ""]))]
    return argv


def _run(argv: list[str]) -> int:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            return main(argv)
        except SystemExit as exit_:  # argparse's usage errors and --help
            return int(exit_.code or 0) if not isinstance(exit_.code, str) else 2


@pytest.mark.timeout(1800)  # thousands of commands: minutes on a loaded machine
def test_every_command_ends_with_an_answer_or_an_error_line(hostile_paths: dict[str, str], tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))  # no launch of this user: looks end after their checks
    monkeypatch.chdir(tmp_path)

    @SETTINGS
    @given(_command_lines(hostile_paths))
    def case(argv: list[str]) -> None:
        outcome: list[int | BaseException] = []

        def run() -> None:
            try:
                outcome.append(_run(argv))
            except BaseException as exc:
                outcome.append(exc)
        worker = threading.Thread(target=run, daemon=True)
        worker.start()
        worker.join(20)
        assert not worker.is_alive(), f"hetros {argv} did not end within 20 s"
        assert outcome and isinstance(outcome[0], int), f"hetros {argv}: {outcome!r}"
        assert outcome[0] != EXIT_BUG, f"hetros {argv} failed unexpectedly (a traceback where an error belongs)"
    case()


@st.composite
def _records(draw: Any) -> tuple[str, bytes]:
    name = draw(st.sampled_from(["123x0000abc.json", "1x" + "a" * 30 + ".json", "../x.json", "x.json",
                                 "123xabcdef12.json"]))
    content = draw(st.one_of(
        st.binary(max_size=200),
        st.recursive(st.one_of(st.none(), st.integers(), st.floats(), st.text(max_size=10)),
                     lambda inner: st.one_of(st.lists(inner, max_size=3),
                                             st.dictionaries(st.text(max_size=8), inner, max_size=3)),
                     max_leaves=10).map(lambda v: json.dumps(v).encode()),
        st.builds(lambda pid, started, host: json.dumps({
            "session": name.removesuffix(".json"), "pid": pid, "started": started, "project": "\x1b]0;owned\x07",
            "root": "/x", "hosts": [host], "host": host}).encode(),
            st.one_of(st.integers(-5, 2**40), st.just(os.getpid())), st.one_of(st.floats(), st.integers()),
            st.text(max_size=5)),
        st.just(b"[" * 100_000)))
    return name, content


@pytest.mark.timeout(1800)
def test_scribbled_registry_records_are_set_aside_never_fatal(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A record another program wrote, or half wrote, or a folder named like one: `hetros ps` and every look
    go on, the bad record moved aside with a warning."""
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    folder = registry_folder()

    @SETTINGS
    @given(_records(), st.booleans())
    def case(record: tuple[str, bytes], as_folder: bool) -> None:
        name, content = record
        target = folder / Path(name).name
        if as_folder and not target.exists():
            target.mkdir()
        elif not target.is_dir():
            target.write_bytes(content)
        launches = running()
        format_launches(launches)
        assert _run(["ps"]) == 0
        for leftover in folder.glob("*.json"):
            assert not leftover.is_dir(), f"{leftover} is still where records are read"
    case()


@pytest.mark.parametrize("argv", [
    ["service", "find", "nan", "--project", "é\x00"],  # found by the 10,000-input soak: a NUL in --project
    ["topic", "list", "--session", "x\x00y"],
    ["init", "/dev/zero", "--root", "nan"],  # found by make test's 2,000: a file outside --root
    ["param", "load", "talker", "/dev/zero"],
])
def test_what_the_soak_found_stays_an_error_line(argv: list[str], tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    assert _run(argv) not in (0, EXIT_BUG)
