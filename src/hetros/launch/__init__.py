"""Launch: start a plan's process targets, supervise them, shut the graph down in order; with hosts,
meet the other hosts and deploy to them.

Three rooms: ``launcher/`` (the launcher, its workers, hosts and the record of running launches),
``system/`` (the nodes the planner adds: gateways and the board surface, the ROS 1 and ROS 2 bridges)
and ``observe/`` (control sockets and taps, inspection, recording and play, Foxglove, logs).

The names below are loaded on first use: a worker process (``python -m hetros.launch.launcher._worker``)
imports this package first and must not pay for the launcher, the project model or transports
its plan does not use.
"""

from typing import TYPE_CHECKING

from .._lazy import lazy_exports

if TYPE_CHECKING:
    from ..hw import SIMULATOR_NICE_VARIABLE
    from .launcher._deploy import deploy, deploy_commands
    from .launcher._hosts import local_host
    from .launcher._launcher import Launcher, LaunchResult, launch
    from .launcher._registry import format_launches, running
    from .observe._bag import describe_played, play, play_launching, record, recordable, recording_info
    from .observe._foxglove import FoxgloveView
    from .observe._inspect import RunningLaunch, TapEvent
    from .observe._logs import LaunchLogs

_WHERE = {
    "Launcher": ".launcher._launcher", "LaunchResult": ".launcher._launcher", "launch": ".launcher._launcher",
    "deploy": ".launcher._deploy", "deploy_commands": ".launcher._deploy", "local_host": ".launcher._hosts",
    "format_launches": ".launcher._registry", "running": ".launcher._registry",
    "describe_played": ".observe._bag", "play": ".observe._bag", "play_launching": ".observe._bag",
    "record": ".observe._bag", "recordable": ".observe._bag", "recording_info": ".observe._bag",
    "FoxgloveView": ".observe._foxglove",
    "RunningLaunch": ".observe._inspect", "TapEvent": ".observe._inspect", "LaunchLogs": ".observe._logs",
    "SIMULATOR_NICE_VARIABLE": "..hw.sim._verilator",
}


__getattr__ = lazy_exports(__name__, _WHERE)



__all__ = [
    "SIMULATOR_NICE_VARIABLE",
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
    "recording_info",
    "running",
]
