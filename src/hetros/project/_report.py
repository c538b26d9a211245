"""What ``hetros check`` found: errors (the plan is refused) and warnings (it is not)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class CheckReport:
    errors: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
