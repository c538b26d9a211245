"""A launch's log lines as its processes write them (``runtime._log.log_to_file``), read as they grow:
by ``hetros log`` and by the bridges that publish them on ROS's ``/rosout``."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

_LINE = re.compile(r"^\[(?P<level>[A-Z]+)\] \[(?P<time>\d+\.\d+)\] \[(?P<name>[^\]]+)\]: (?P<message>.*)$")


@dataclass(frozen=True, order=True)
class LogRecord:
    """One record: wall time, writer (a node, or hetros's ``launch``), level, the message, and the
    whole text as written (its continuation lines included)."""

    time: float
    name: str
    level: str
    message: str
    text: str


class LogFile:
    """One process' log of a launch, read as it grows; records keep their continuation lines."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.offset = 0
        self.partial = ""

    def new_records(self) -> list[LogRecord]:
        try:
            with self.path.open("r", encoding="utf-8", errors="replace") as handle:
                handle.seek(self.offset)
                text = handle.read()
                self.offset = handle.tell()
        except OSError:
            return []
        text, self.partial = self.partial + text, ""
        if not text.endswith("\n"):
            text, _, self.partial = text.rpartition("\n")
        records: list[LogRecord] = []
        for line in text.splitlines():
            match = _LINE.match(line)
            if match:
                records.append(LogRecord(float(match["time"]), match["name"], match["level"], match["message"], line))
            elif records:
                last = records[-1]
                records[-1] = LogRecord(last.time, last.name, last.level, f"{last.message}\n{line}",
                                        f"{last.text}\n{line}")
        return records


class LaunchLogs:
    """Every process' log of one launch (``folder``), new records merged in time on each read."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._files: dict[Path, LogFile] = {}

    def new_records(self) -> list[LogRecord]:
        for path in sorted(self.folder.glob("*.log")):
            self._files.setdefault(path, LogFile(path))
        return sorted(record for log in self._files.values() for record in log.new_records())
