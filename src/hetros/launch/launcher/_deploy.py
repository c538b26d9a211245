"""``hetros deploy``: start every host's share of a project from one machine, stop them together.

Each host runs the same checkout of the project at the same path (the project hash
check refuses anything else). This machine's host is launched directly; every other
host over ssh (``hosts: <name>: {ssh: <user>}``), in a terminal (``-tt``) so that
stopping the local ssh hangs up the remote launcher, which then stops in order.
"""

from __future__ import annotations

import shlex
import signal
import subprocess
import sys
import threading
from pathlib import Path

from ..._errors import LaunchError
from ..._signals import wait_until_set
from ...plan import Plan
from ._hosts import local_host


def deploy_commands(plan: Plan, project: Path, *, remote: str = "python3 -m hetros",
                    duration: float | None = None) -> dict[str, list[str]]:
    """The command that starts each host's share: this machine's directly, the others over ssh."""
    if not plan.hosts:
        raise LaunchError("the project names no hosts: run it with `hetros launch`")
    try:
        here = local_host(plan)
    except LaunchError:
        here = ""
    project = project.resolve()
    commands = {}
    for name, host in plan.hosts.items():
        extra = ["--duration", f"{duration:g}"] if duration is not None else []
        if name == here:
            commands[name] = [sys.executable, "-m", "hetros", "launch", str(project), "--as", name, *extra]
            continue
        if not host.ssh:
            raise LaunchError(f"host {name} ({host.address}) is not this machine and has no ssh user: add "
                              f"'ssh: <user>' under hosts: {name}:, or start it there with "
                              f"`hetros launch {project.name} --as {name}`")
        remote_line = (f"cd {shlex.quote(str(project.parent))} && "
                       f"{remote} launch {shlex.quote(str(project))} --as {name} {shlex.join(extra)}").rstrip()
        commands[name] = ["ssh", "-tt", "-o", "BatchMode=yes", "-l", host.ssh, host.address, remote_line]
    return commands


def deploy(plan: Plan, project: Path, *, remote: str = "python3 -m hetros", duration: float | None = None) -> int:
    """Run every host's command, prefix their output with the host, stop all on Ctrl-C or when one
    ends; the exit code is the worst of theirs."""
    commands = deploy_commands(plan, project, remote=remote, duration=duration)
    processes: dict[str, subprocess.Popen[str]] = {}
    ended = threading.Event()

    def relay(name: str, process: subprocess.Popen[str]) -> None:
        assert process.stdout is not None
        for line in process.stdout:
            sys.stdout.write(f"[{name}] {line}")
            sys.stdout.flush()
        process.wait()
        ended.set()

    for name, command in commands.items():
        processes[name] = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                                           stdin=subprocess.DEVNULL)
        threading.Thread(target=relay, args=(name, processes[name]), daemon=True).start()
    try:
        wait_until_set(ended)
    except KeyboardInterrupt:
        pass
    for process in processes.values():
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
    codes = []
    for name, process in processes.items():
        try:
            codes.append(process.wait(timeout=20))
        except subprocess.TimeoutExpired:
            sys.stderr.write(f"[deploy] host {name} did not stop within 20 s; killing its launcher\n")
            process.kill()
            codes.append(process.wait())
    return max((abs(code) for code in codes), default=0)
