"""Launch: start a plan's process targets, supervise them, shut the graph down in order; with hosts,
meet the other hosts and deploy to them."""

from ._deploy import deploy, deploy_commands
from ._hosts import local_host
from ._launcher import Launcher, LaunchResult, launch

__all__ = ["LaunchResult", "Launcher", "deploy", "deploy_commands", "launch", "local_host"]
