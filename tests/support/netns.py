"""Network namespaces joined by a bridge: machines for the multi-host tests, made and torn down here.

Each namespace gets a veth pair into one bridge in the root namespace and an address of
its own, so traffic between them is real IP between distinct interfaces. The namespaces
share the file system and /dev/shm (so the test must show that edges between them went
over DDS, not shared memory).
"""

from __future__ import annotations

import itertools
import os
import shutil
import subprocess
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass


@dataclass(frozen=True)
class Namespace:
    name: str
    address: str

    def command(self, *argv: str) -> list[str]:
        return ["ip", "netns", "exec", self.name, *argv]


def _ip(*argv: str) -> None:
    subprocess.run(["ip", *argv], check=True, capture_output=True, text=True)


def unavailable() -> str:
    """Why namespaces cannot be made here ('' when they can)."""
    if shutil.which("ip") is None:
        return "iproute2's `ip` is not installed"
    if os.geteuid() != 0:
        return "making network namespaces needs root"
    probe = f"htprobe{os.getpid()}"
    made = subprocess.run(["ip", "netns", "add", probe], capture_output=True, text=True)
    if made.returncode != 0:
        return f"`ip netns add` failed: {made.stderr.strip()}"
    subprocess.run(["ip", "netns", "del", probe], capture_output=True)
    return ""


_made = itertools.count()


@contextmanager
def namespaces(count: int) -> Iterator[list[Namespace]]:
    # names of their own per call: the kernel removes a deleted namespace's links asynchronously
    tag = f"{os.getpid() % 1000}{next(_made) % 100}"
    bridge = f"htbr{tag}"
    subnet = f"10.{77 + os.getpid() % 100}.{os.getpid() % 250}"
    made: list[Namespace] = []
    _ip("link", "add", bridge, "type", "bridge")
    try:
        _ip("link", "set", bridge, "up")
        for index in range(count):
            space = Namespace(f"ht{tag}n{index}", f"{subnet}.{index + 1}")
            outside, inside = f"ht{tag}v{index}", f"ht{tag}p{index}"
            _ip("netns", "add", space.name)
            made.append(space)
            _ip("link", "add", outside, "type", "veth", "peer", "name", inside)
            _ip("link", "set", outside, "master", bridge)
            _ip("link", "set", outside, "up")
            _ip("link", "set", inside, "netns", space.name)
            _ip("-n", space.name, "addr", "add", f"{space.address}/24", "dev", inside)
            _ip("-n", space.name, "link", "set", inside, "up")
            _ip("-n", space.name, "link", "set", "lo", "up")
        yield made
    finally:
        for space in made:
            subprocess.run(["ip", "netns", "del", space.name], capture_output=True)
        subprocess.run(["ip", "link", "del", bridge], capture_output=True)
