"""Run by ``_stale.py`` in a child process of its own: iceoryx2 removes dead nodes' resources here.

``try_remove_stale_resources`` maps the segments a dead node left; one damaged by the crash
made it die of SIGBUS or SIGSEGV, which took every launch on the machine down with it. Here a
crash ends this child only: before each node it prints ``begin <id>``, after it ``done <id>``,
so the parent knows which node killed it and removes that one's files by path.

Usage: ``python _stale_child.py ROOT PREFIX NODE_ID...`` (it imports iceoryx2 and nothing of
hetros, to start fast).
"""

from __future__ import annotations

import os
import sys


def main(argv: list[str]) -> int:
    root, prefix, *wanted = argv
    os.environ.setdefault("IOX2_LOG_LEVEL", "Error")
    import iceoryx2 as iox2

    iox2.set_log_level(iox2.LogLevel.Error)
    config = iox2.config.default()
    config.global_cfg.root_path = iox2.Path.new(root)
    config.global_cfg.prefix = iox2.FileName.new(prefix)
    wanted_ids = set(wanted)
    for state in iox2.Node.list(iox2.ServiceType.Ipc, config):
        view = state._0
        node_id = str(view.id.value)
        if node_id not in wanted_ids:
            continue
        if type(state).__name__ != "Dead":
            print(f"alive {node_id}", flush=True)
            continue
        print(f"begin {node_id}", flush=True)
        view.try_remove_stale_resources()
        print(f"done {node_id}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
