"""Where in the user's code a call into hetros's ROS modules comes from: a refusal names that line."""

from __future__ import annotations

import sys
from pathlib import Path

_HERE = str(Path(__file__).resolve().parent)  # hetros/compat: the shims' own frames are skipped


def caller_place() -> str:
    """``file:line`` of the first frame outside hetros's ROS modules (the user's call)."""
    frame = sys._getframe(1)
    while frame is not None and frame.f_code.co_filename.startswith(_HERE):
        frame = frame.f_back  # type: ignore[assignment]
    return f"{frame.f_code.co_filename}:{frame.f_lineno}" if frame is not None else "<unknown>"


__all__ = ["caller_place"]
