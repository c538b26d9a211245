"""Reading a file a user, or another account, can name (below every layer).

Project files, launch records, plans, profiles, launch files and their includes, parameter
files, `init` sources, calibrations and recordings are all named on a command line or inside
another file, so any of them may be a FIFO (a read that never ends), /dev/zero (one that never
stops), a folder, a 1.5 GB sparse file, JSON nested 100,000 deep or YAML whose aliases expand
a few lines into billions of nodes. Every reader goes through here: a path must be a regular
file, its size is capped before it is read, nesting is capped while it is parsed, and every
way decoding fails becomes one line naming the file and what to do.
"""

from __future__ import annotations

import json
import os
import stat
from functools import cache
from pathlib import Path
from typing import Any

from ._errors import Error, InputFileError

# what a text file hetros reads may hold; a project with its launch files is kilobytes
TEXT_LIMIT = 16 << 20
# nesting of YAML and JSON values: a project file goes ~8 deep, a plan ~10
DEPTH_LIMIT = 64
# YAML nodes after aliases are followed: a large parameter file holds tens of thousands
NODE_LIMIT = 1_000_000

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


_CONTROL = {code: f"\\x{code:02x}" for code in [*range(0x20), 0x7F, *range(0x80, 0xA0)] if code not in (0x09, 0x0A)}


def printable(text: str) -> str:
    """``text`` with control characters escaped (``\\x1b``): text read from files or records goes to a
    terminal, where an escape sequence could clear the screen or retitle the window."""
    return text.translate(_CONTROL)


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def check_regular(path: str | Path, what: str, *, error: type[Error] = InputFileError) -> None:
    """Refuse ``path`` by name unless it is a regular file (for readers that open it themselves)."""
    read_bytes(path, what, limit=-1, error=error)


def read_bytes(path: str | Path, what: str, *, limit: int = TEXT_LIMIT,
               error: type[Error] = InputFileError) -> bytes:
    """The bytes of the regular file ``path`` (``what`` it is for the message), at most ``limit``.

    Opened without blocking, so a FIFO is named instead of waited on; the size is checked on
    the open file, so a file swapped after a check is still the one judged."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except IsADirectoryError:
        raise error(f"{what} {path} is a folder, not a file; name the file inside it") from None
    except FileNotFoundError:
        raise error(f"{what} {path} does not exist") from None
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror}") from None
    except ValueError:
        raise error(f"{what} {str(path)!r} is not a path (it holds a NUL character)") from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{what} {path} is {_kind(info.st_mode)}, not a file; name a regular file")
        if limit < 0:
            return b""  # only checked
        if info.st_size > limit:
            raise error(f"{what} {path} is {info.st_size:,} bytes, more than such a file can be "
                        f"({limit:,}); name the right file")
        chunks, total = [], 0
        while chunk := os.read(fd, min(1 << 20, limit + 1 - total)):
            chunks.append(chunk)
            total += len(chunk)
            if total > limit:
                raise error(f"{what} {path} grew past {limit:,} bytes while it was read; name a file that "
                            "holds still")
        return b"".join(chunks)
    except OSError as exc:
        raise error(f"cannot read {what} {path}: {exc.strerror}") from None
    finally:
        os.close(fd)


def read_text(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> str:
    """:func:`read_bytes` decoded as UTF-8, a bad byte named by its offset."""
    data = read_bytes(path, what, limit=limit, error=error)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not UTF-8 text (byte {exc.start:,} is {data[exc.start]:#04x}); is it "
                    "the right file?") from None


def check_depth(value: Any, what: str, *, limit: int = DEPTH_LIMIT, error: type[Error] = InputFileError) -> Any:
    """``value`` (parsed JSON or YAML) when no list or mapping in it is nested deeper than ``limit``,
    walked without recursion so that the check itself cannot overflow the stack."""
    stack: list[tuple[Any, int]] = [(value, 1)]
    seen: set[int] = set()
    while stack:
        item, depth = stack.pop()
        if isinstance(item, dict | list):
            if depth > limit:
                raise error(f"{what} is nested more than {limit} levels deep; no such file is")
            if id(item) in seen:
                continue  # a YAML alias: shared, walked once
            seen.add(id(item))
            stack.extend((child, depth + 1) for child in (item.values() if isinstance(item, dict) else item))
    return value


def parse_json(text: str | bytes, what: str, *, error: type[Error] = InputFileError) -> Any:
    """JSON ``text`` from ``what``, its nesting capped."""
    try:
        value = json.loads(text)
    except RecursionError:
        raise error(f"{what} is nested more deeply than Python can parse; no such file is") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise error(f"{what} is not JSON ({exc})") from None
    return check_depth(value, what, error=error)


@cache
def _counting_loader() -> Any:
    """yaml's safe loader that counts the nodes it composes, an alias once per use, so that a few lines of
    aliases cannot stand for billions of values (made on first use: a worker that reads no YAML loads no yaml)."""
    import yaml

    class CountingLoader(yaml.SafeLoader):
        def __init__(self, stream: str) -> None:
            super().__init__(stream)
            self.composed = 0
            self.depth = 0

        def compose_node(self, parent: Any, index: Any) -> Any:
            self.composed += 1
            if self.composed > NODE_LIMIT:
                raise yaml.YAMLError(f"more than {NODE_LIMIT:,} values (aliases counted at each use)")
            self.depth += 1
            try:
                if self.depth > DEPTH_LIMIT:
                    raise yaml.YAMLError(f"nested more than {DEPTH_LIMIT} levels deep; no such file is")
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1
    return CountingLoader


def _expanded_size(value: Any) -> int:
    """How many values ``value`` stands for with every alias expanded, counted without expanding."""
    sizes: dict[int, int] = {}

    def size(item: Any) -> int:
        if not isinstance(item, dict | list):
            return 1
        known = sizes.get(id(item))
        if known is None:
            children = item.values() if isinstance(item, dict) else item
            known = sizes[id(item)] = 1 + sum(size(child) for child in children)
        return known

    return size(value)


def parse_yaml(text: str, what: str, *, error: type[Error] = InputFileError) -> Any:
    """YAML ``text`` from ``what`` (safe: no Python objects), nesting and alias expansion capped."""
    import yaml

    try:
        loader = _counting_loader()(text)
    except yaml.YAMLError as exc:  # the reader refuses the text before parsing (a NUL, a control character)
        raise error(f"{what} is not valid YAML: {exc}") from None
    try:
        value = loader.get_single_data()
    except RecursionError:
        raise error(f"{what} is nested more deeply than Python can parse; no such file is") from None
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark
        where = f":{mark.line + 1}:{mark.column + 1}" if mark is not None else ""
        raise error(f"{what}{where} is not valid YAML: {exc.problem or exc}") from None
    except yaml.YAMLError as exc:
        raise error(f"{what} is not valid YAML: {exc}") from None
    finally:
        loader.dispose()
    check_depth(value, what, error=error)
    if _expanded_size(value) > NODE_LIMIT:
        raise error(f"{what} stands for more than {NODE_LIMIT:,} values once its aliases are expanded; "
                    "write the values out")
    return value


def parse_python(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> Any:
    """The syntax tree (``ast.Module``) of the Python file ``path``; a syntax error named by its line,
    code nested past what the parser takes refused."""
    import ast

    text = read_text(path, what, limit=limit, error=error)
    try:
        return ast.parse(text, filename=str(path))
    except SyntaxError as exc:
        raise error(f"{path}:{exc.lineno or 1}: {what} is not valid Python ({exc.msg}); fix it, or name "
                    "another file") from None
    except (RecursionError, MemoryError, ValueError) as exc:
        raise error(f"{what} {path} cannot be parsed ({type(exc).__name__}: {exc}); is it the right file?") from None


def dataclass_problem(value: Any, where: str) -> str | None:
    """Where a dataclass built from a file (a plan, a profile) holds a value its annotations do not allow
    (``plan.nodes.x.args.0: 3 is not str``), else None: checked once, where the file is read, so that a
    changed or forged file is named there and not where a value of the wrong kind is first used."""
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        for name, hint in _field_hints(type(value)):
            found = _value_problem(getattr(value, name), hint, f"{where}.{name}")
            if found is not None:
                return found
    return None


@cache
def _field_hints(kind: type) -> tuple[tuple[str, Any], ...]:
    import dataclasses
    import typing

    hints = typing.get_type_hints(kind)
    return tuple((item.name, hints[item.name]) for item in dataclasses.fields(kind))


def _value_problem(value: Any, hint: Any, where: str) -> str | None:
    import dataclasses
    import types
    import typing

    origin, args = typing.get_origin(hint), typing.get_args(hint)
    if hint is Any:
        return None
    if origin in (typing.Union, types.UnionType):
        problems = [_value_problem(value, option, where) for option in args]
        return None if any(p is None for p in problems) else problems[0]
    if origin is typing.Literal:
        return None if value in args else f"{where}: {value!r} is not one of {args}"
    if origin is tuple:
        if not isinstance(value, tuple):
            return f"{where}: {value!r} is not a list"
        return next((p for i, v in enumerate(value) if (p := _value_problem(v, args[0], f"{where}.{i}"))), None)
    if origin is dict:
        if not isinstance(value, dict):
            return f"{where}: {value!r} is not a mapping"
        return next((p for k, v in value.items() if (p := _value_problem(k, args[0], f"{where}.{k}") or
                                                      _value_problem(v, args[1], f"{where}.{k}"))), None)
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        if not isinstance(value, hint):
            return f"{where}: {value!r} is not a {hint.__name__}"
        return dataclass_problem(value, where)
    if hint is float:
        ok = isinstance(value, int | float) and not isinstance(value, bool)
    elif hint is int:
        ok = isinstance(value, int) and not isinstance(value, bool)
    else:
        ok = isinstance(value, hint) if isinstance(hint, type) else True
    return None if ok else f"{where}: {value!r} is not {getattr(hint, '__name__', hint)}"


def load_json(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> Any:
    return parse_json(read_bytes(path, what, limit=limit, error=error), f"{what} {path}", error=error)


def load_yaml(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> Any:
    return parse_yaml(read_text(path, what, limit=limit, error=error), f"{what} {path}", error=error)


__all__ = ["DEPTH_LIMIT", "TEXT_LIMIT", "check_depth", "check_regular", "dataclass_problem", "load_json", "load_yaml",
           "parse_json", "parse_python", "parse_yaml", "printable", "read_bytes", "read_text"]
