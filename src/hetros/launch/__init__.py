"""Launch: start a plan's process targets, supervise them, shut the graph down in order; with hosts,
meet the other hosts and deploy to them.

The names below are loaded on first use: a worker process (``python -m hetros.launch._worker``)
imports this package first and must not pay for the launcher, the project model or transports
its plan does not use.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._bag import describe_played, play, play_launching, record, recordable
    from ._deploy import deploy, deploy_commands
    from ._foxglove import FoxgloveView
    from ._hosts import local_host
    from ._inspect import RunningLaunch, TapEvent
    from ._launcher import Launcher, LaunchResult, launch
    from ._logs import LaunchLogs
    from ._registry import format_launches, running

_WHERE = {"deploy": "_deploy", "deploy_commands": "_deploy", "local_host": "_hosts", "Launcher": "_launcher",
          "LaunchResult": "_launcher", "launch": "_launcher", "describe_played": "_bag", "play": "_bag",
          "play_launching": "_bag", "record": "_bag", "recordable": "_bag", "FoxgloveView": "_foxglove",
          "RunningLaunch": "_inspect", "TapEvent": "_inspect", "LaunchLogs": "_logs", "format_launches": "_registry",
          "running": "_registry"}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f"{__name__}.{module}"), name)



__all__ = [
    "FoxgloveView",
    "LaunchLogs",
    "LaunchResult",
    "Launcher",
    "RunningLaunch",
    "TapEvent",
    "deploy",
    "deploy_commands",
    "describe_played",
    "format_launches",
    "launch",
    "local_host",
    "play",
    "play_launching",
    "record",
    "recordable",
    "running",
]
