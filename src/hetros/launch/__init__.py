"""Launch: start a plan's process targets, supervise them, shut the graph down in order."""

from ._launcher import Launcher, LaunchResult, launch

__all__ = ["LaunchResult", "Launcher", "launch"]
