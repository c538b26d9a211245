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
from pathlib import Path
from typing import Any

import yaml

from ._errors import Error, InputFileError

# what a text file hetros reads may hold; a project with its launch files is kilobytes
TEXT_LIMIT = 16 << 20
# nesting of YAML and JSON values: a project file goes ~8 deep, a plan ~10
DEPTH_LIMIT = 64
# YAML nodes after aliases are followed: a large parameter file holds tens of thousands
NODE_LIMIT = 1_000_000

_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"))


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


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
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            raise error(f"{what} {path} is {_kind(info.st_mode)}, not a file; name a regular file")
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


class _CountingLoader(yaml.SafeLoader):
    """yaml's safe loader that counts the nodes it composes, an alias once per use, so that a
    few lines of aliases cannot stand for billions of values."""

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
    loader = _CountingLoader(text)
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


def load_json(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> Any:
    return parse_json(read_bytes(path, what, limit=limit, error=error), f"{what} {path}", error=error)


def load_yaml(path: str | Path, what: str, *, limit: int = TEXT_LIMIT, error: type[Error] = InputFileError) -> Any:
    return parse_yaml(read_text(path, what, limit=limit, error=error), f"{what} {path}", error=error)


__all__ = ["DEPTH_LIMIT", "TEXT_LIMIT", "check_depth", "load_json", "load_yaml", "parse_json", "parse_yaml",
           "read_bytes", "read_text"]
