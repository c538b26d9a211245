"""Entry point of a process target: ``python -m hetros.launch.launcher._worker``.

The launcher passes the plan as a JSON file (never pickle), talks over stdin
("go", "stop"; end of input means the launcher died, so the worker stops) and
reads JSON status lines from a pipe.
"""

from __future__ import annotations

import argparse
import faulthandler
import json
import os
import signal
import sys
import threading
from pathlib import Path
from typing import Any

from ..._signals import wait_until_set
from ...compat import install as install_ros_names
from ...plan import Plan
from ...runtime import Host, setup_logging


def _remove_session_segments(session: str) -> None:
    """The launcher died: remove the session's shared memory (loaded here, on that path only, so a
    worker whose edges use no shared memory never loads iceoryx2)."""
    from ...transport import remove_session_segments

    remove_session_segments(session)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="hetros-worker")
    parser.add_argument("--plan", required=True)
    parser.add_argument("--target", required=True)
    parser.add_argument("--session", required=True)
    parser.add_argument("--status-fd", type=int, required=True)
    args = parser.parse_args(argv)
    faulthandler.enable()  # a crash in native code (a damaged segment, an extension) names itself on stderr
    setup_logging()
    from ...runtime import log_to_file
    from ._registry import session_folder

    try:
        plan = Plan.from_json(Path(args.plan).read_text(encoding="utf-8"))
    except OSError:  # the launcher stopped (an early Ctrl-C) and took its plan file along: an orderly end
        sys.stderr.write(f"[INFO] [{args.target}]: the launch stopped before this target started\n")
        return 0
    log_to_file(session_folder(args.session) / f"{args.target}.log")
    status = os.fdopen(args.status_fd, "w", buffering=1)
    lock = threading.Lock()

    def report(event: str, **fields: Any) -> None:
        with lock:
            try:
                status.write(json.dumps({"event": event, "target": args.target, **fields}) + "\n")
            except (BrokenPipeError, ValueError):
                pass  # the launcher is gone; what matters now is stopping cleanly

    cpus = plan.targets[args.target].cpus
    if cpus:
        os.sched_setaffinity(0, cpus)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    go = threading.Event()
    orphaned = threading.Event()
    stop_reason = [""]
    hosts: list[Host] = []  # the host once built: a stop's reason reaches its graph before the stop

    def control() -> None:
        """The launcher's word, heard from the start: a stop during start-up (a ROS master that
        is not there, a slow import) ends the start instead of waiting to be killed."""
        for line in sys.stdin:
            if line.strip() == "go":
                go.set()
            elif line.split(" ", 1)[0].strip() == "stop":
                stop_reason[0] = line[4:].strip()
                for built in hosts:
                    built.graph.stop_reason = stop_reason[0]
                break
        else:
            orphaned.set()  # end of input without "stop": the launcher died
        stop.set()

    threading.Thread(target=control, name="control", daemon=True).start()
    try:
        install_ros_names()  # rclpy and ROS message packages for the nodes written for ROS
        host = Host(plan, args.target, args.session,
                    lambda node, tb, restarting: report("node_failed", node=node, traceback=tb,
                                                        restarting=restarting), stop, stop.set,
                    lambda node, unheard: report("node_done", node=node, unheard=unheard),
                    lambda node, seconds: report("preparing", node=node) if seconds is None else
                    report("prepared", node=node, seconds=seconds))
    except Exception as exc:
        import traceback

        if not stop.is_set():
            report("start_failed", error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc())
        else:
            sys.stderr.write(f"[WARN] [{args.target}]: stopped while starting: {type(exc).__name__}: {exc}\n")
        if orphaned.is_set():
            _remove_session_segments(args.session)
        return 2
    hosts.append(host)
    host.graph.announce_hooks = lambda: report("hooks")
    from ..observe._control import ControlServer

    looks = ControlServer(host, session_folder(args.session), args.target)
    host.graph.stop_reason = stop_reason[0]
    report("ready", pid=os.getpid(), cpus=sorted(os.sched_getaffinity(0)))
    while not stop.is_set():
        if go.wait(0.05):
            host.start()
            break
    wait_until_set(stop)
    looks.close()
    stuck = host.stop()
    failed = [t.spec.name for t in host.threads if t.failed and not t.spec.optional]
    if host.unacknowledged:
        failed.append(f"target {args.target} (reliable messages left untaken)")
    report("stopped", stuck=stuck, failed=failed)
    try:
        status.close()
    except BrokenPipeError:
        pass
    if orphaned.is_set():
        # nobody else will clean up after the launcher: every worker removes what it can
        sys.stderr.write(f"[WARN] [{args.target}]: the launcher is gone; stopped and cleaned up\n")
        _remove_session_segments(args.session)
        Path(args.plan).unlink(missing_ok=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
