"""The first line of every benchmark report: when, on what machine and with which command.

Figures move with the machine, so a table pasted into the docs carries where it came from.
"""

from __future__ import annotations

import datetime
import os
import platform
import shlex
import sys


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def provenance(command: str | None = None) -> str:
    """``_Measured <UTC time> on <CPU>, <n> CPUs, Linux <release>, Python <version>: `<command>`._``"""
    when = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    if command is None:
        program = sys.argv[0]
        program = "hetros" if program.endswith(("hetros", "__main__.py")) else program
        command = " ".join([shlex.quote(program), *map(shlex.quote, sys.argv[1:])])
    return (f"_Measured {when} on {_cpu_model()}, {os.cpu_count()} CPUs, {platform.system()} "
            f"{platform.release()}, Python {platform.python_version()}: `{command}`._")
