"""Launch: start a plan's process targets, supervise them, shut the graph down in order; with hosts,
meet the other hosts and deploy to them.

The names below are loaded on first use: a worker process (``python -m hetros.launch._worker``)
imports this package first and must not pay for the launcher, the project model or transports
its plan does not use.
"""

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ._deploy import deploy, deploy_commands
    from ._hosts import local_host
    from ._launcher import Launcher, LaunchResult, launch

_WHERE = {"deploy": "_deploy", "deploy_commands": "_deploy", "local_host": "_hosts", "Launcher": "_launcher",
          "LaunchResult": "_launcher", "launch": "_launcher"}


def __getattr__(name: str) -> Any:
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


__all__ = ["LaunchResult", "Launcher", "deploy", "deploy_commands", "launch", "local_host"]
