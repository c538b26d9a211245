"""iceoryx2, imported once with its logging quietened (it prints to stderr otherwise), and the
configuration every hetros process gives it.

iceoryx2's default root (``/tmp/iceoryx2``) is shared by every account and takes the mode of
whoever made it first, which locked every other account out of shared memory; and one damaged
leftover there stopped every later launch on the machine. hetros gives it a root in this
user's private folder (``hetros._paths``) and file names of this user's (``hx<uid><secret>_`` in
``/dev/shm``), so accounts never meet, and a clean-up only ever looks at this user's files.
"""

from __future__ import annotations

import functools
import importlib
import os
import stat
from pathlib import Path
from typing import Any

os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
import iceoryx2 as iox2

from ..._log import get_logger
from ..._paths import user_subfolder
from ._sample import SHM_DIR, file_prefix

iox2.set_log_level(iox2.LogLevel.Error)

log = get_logger("hetros.transport.shm")
try:  # CPython's own SHA-1: hashlib would map OpenSSL (3 MB in every worker) to name a service
    _sha1: Any = importlib.import_module("_sha1").sha1
except ImportError:  # an interpreter built without it
    _sha1 = importlib.import_module("hashlib").sha1


def sha1(data: bytes) -> Any:
    """SHA-1 of a name's parts (services and events are named by digests of session, topic and target)."""
    return _sha1(data)

# The binding's Python wrappers recheck the payload type on every call (~0.3 µs each). Every
# hetros service carries byte slices, so the hot path calls the methods they wrap, when this
# version of the binding has them (tests/conformance/test_shm_specific.py notices a rename).
loan_slice = getattr(iox2.Publisher, "__loan_slice_uninit", iox2.Publisher.loan_slice_uninit)
assume_init = getattr(iox2.SampleMutUninit, "__assume_init", iox2.SampleMutUninit.assume_init)

# iceoryx2 names its event sockets under the root with some 60 bytes of its own: a Unix socket's
# path holds 107
_ROOT_LENGTH = 40


def iceoryx_root() -> Path:
    """iceoryx2's root folder for this user (nodes, services, event sockets), checked private."""
    return user_subfolder("iceoryx2", max_length=_ROOT_LENGTH)


def shm_config() -> Any:
    """iceoryx2's configuration for the nodes of this user (its root and names follow ``XDG_RUNTIME_DIR``)."""
    return _config_at(str(iceoryx_root()), file_prefix())


@functools.cache
def _config_at(root: str, prefix: str) -> Any:
    config = iox2.config.default()
    config.global_cfg.root_path = iox2.Path.new(f"{root}/")
    config.global_cfg.prefix = iox2.FileName.new(prefix)
    # iceoryx2 would clean dead nodes inside every process that makes or drops a node, where one
    # damaged segment kills it; the launcher does it in a child process instead (``_stale.py``)
    config.global_cfg.node.cleanup_dead_nodes_on_creation = False
    config.global_cfg.node.cleanup_dead_nodes_on_destruction = False
    return config


def new_node(name: str) -> Any:
    """An iceoryx2 node of this process, signals left to hetros, under this user's root. iceoryx2 makes its
    node counter (``*global_mgmt`` in /dev/shm) writable by every account: it is closed to this user's."""
    node = (iox2.NodeBuilder.new().name(iox2.NodeName.new(name[:120])).config(shm_config())
            .signal_handling_mode(iox2.SignalHandlingMode.Disabled).create(iox2.ServiceType.Ipc))
    close_node_counters()
    return node


def node_counters() -> list[Path]:
    """iceoryx2's machine-wide node counters under this user's names."""
    return sorted(SHM_DIR.glob(f"{file_prefix()}*global_mgmt"))


def close_node_counters() -> None:
    for path in node_counters():
        try:
            info = path.lstat()
            if info.st_uid == os.getuid() and stat.S_IMODE(info.st_mode) & 0o077:
                os.chmod(path, 0o600)
        except OSError:
            continue


__all__ = ["assume_init", "close_node_counters", "file_prefix", "iceoryx_root", "iox2", "loan_slice", "log", "new_node",
           "node_counters", "shm_config"]
