"""Starts a plan's targets, supervises them, and shuts the graph down in order.

Threads run in this process; each process target is a fresh interpreter
(``subprocess``, the spawn model: nothing inherited but the plan file), pinned
to its cpus. Start-up has a barrier: every process first imports its nodes
and opens its transports, then all nodes start together. Shutdown is the
reverse: stop every node, wait, then remove the shared memory of the session.
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import shutil
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from ..._errors import Error, LaunchError
from ..._log import get_logger
from ..._net import is_local_address
from ..._process import death_cause
from ..._signals import next_item
from ...compat import install as install_ros_names
from ...plan import LAUNCHER, Plan
from ...runtime import Host, log_to_file, setup_logging, stop_logging_to
from ...transport import check_room, cleanup_stale, new_session, remove_session_segments, reserved_bytes
from ..observe._control import ControlServer
from ._hosts import HostLink, local_host
from ._registry import register, session_folder, unregister, write_private

log = get_logger("hetros.launch")


# seconds the targets may take to start (import, open endpoints), their announced preparation not counted
START_TIMEOUT = 60.0


@dataclass
class LaunchResult:
    exit_code: int
    failures: list[str] = field(default_factory=list)
    reason: str = ""


@dataclass
class _Child:
    target: str
    proc: subprocess.Popen[str]
    status: IO[str]
    ready: bool = False
    stopping: bool = False
    reader: threading.Thread | None = None
    hooks: bool = False  # its nodes have shutdown hooks: stopped before the others (``_shutdown``)


class Launcher:
    def __init__(self, plan: Plan, *, duration: float | None = None, record: Path | None = None,
                 start_timeout: float = START_TIMEOUT) -> None:
        self.plan = plan
        self.start_timeout = start_timeout
        self.record_to = record
        self._recorder: threading.Thread | None = None
        self.duration = duration
        self.session = new_session()
        self.events: queue.Queue[dict[str, Any]] = queue.Queue()
        self.children: dict[str, _Child] = {}
        self.failures: list[str] = []
        self.stop = threading.Event()
        self.host: Host | None = None
        self.link: HostLink | None = None
        self._plan_file: Path | None = None
        self.control: ControlServer | None = None

    # -- start -----------------------------------------------------------------------------

    def _spawn(self, target: str) -> _Child:
        assert self._plan_file is not None
        read_fd, write_fd = os.pipe()
        cmd = [sys.executable, "-m", "hetros.launch.launcher._worker", "--plan", str(self._plan_file),
               "--target", target, "--session", self.session, "--status-fd", str(write_fd)]
        env = dict(os.environ) | self.plan.env_of(target)
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [self.plan.root, *self.plan.python_path,
                                                          env.get("PYTHONPATH", "")]))
        proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, pass_fds=(write_fd,), text=True, env=env,
                                start_new_session=True)
        os.close(write_fd)
        child = _Child(target, proc, os.fdopen(read_fd, "r"))
        child.reader = threading.Thread(target=self._read_status, args=(child,), daemon=True)
        child.reader.start()
        threading.Thread(target=self._watch_exit, args=(child,), daemon=True).start()
        return child

    def _read_status(self, child: _Child) -> None:
        for line in child.status:
            try:
                event = json.loads(line)
            except json.JSONDecodeError:
                continue
            if isinstance(event, dict) and event.get("event") == "hooks":
                child.hooks = True
            elif isinstance(event, dict):
                self.events.put(event)

    def _watch_exit(self, child: _Child) -> None:
        code = child.proc.wait()
        self.events.put({"event": "exited", "target": child.target, "code": code})

    def _local_failure(self, node: str, tb: str, restarting: bool) -> None:
        self.events.put({"event": "node_failed", "target": self.plan.nodes[node].target, "node": node,
                         "traceback": tb,
                         "restarting": restarting})

    def run(self) -> LaunchResult:
        # first: a stop from here on is an event the supervisor handles in order (before, the command's
        # own handler ended the process at once, when nothing had been made yet). SIGHUP: `hetros deploy`
        # stops a remote host by hanging up its ssh terminal
        previous = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
        in_main = threading.current_thread() is threading.main_thread()
        if in_main:
            for sig in previous:
                signal.signal(sig, lambda *_: self.events.put({"event": "signal"}))
        try:
            setup_logging()
            logged = log_to_file(session_folder(self.session) / f"{LAUNCHER}.log")
            cleanup_stale()
            self._plan_file = session_folder(self.session) / "plan.json"
            write_private(self._plan_file, self.plan.to_json())
        except BaseException:
            if in_main:
                for sig, handler in previous.items():
                    signal.signal(sig, handler)
            with contextlib.suppress(Error):
                unregister(self.session)
            raise
        result = LaunchResult(130, [], "interrupted during start-up")
        try:
            register(self.session, self.plan)
            result = self._supervise()
        except KeyboardInterrupt:
            pass
        except (RuntimeError, MemoryError, OSError) as exc:  # no thread, process or memory to be had
            cause = f"{type(exc).__name__}: {exc}"
            sys.stderr.write(f"[ERROR] [launch]: the launch ran out of resources ({cause}): the machine or its "
                             "limits (ulimit -v / -u, a cgroup's memory.max) leave no room for the graph's "
                             "threads and processes; raise them or spread the nodes over fewer processes\n")
            result = LaunchResult(1, [], f"out of resources ({cause})")
        finally:
            unregister(self.session)
            if self.link is not None:
                self.link.announce("leaving", ok=result.exit_code == 0, why=result.reason)
            failed_before = len(self.failures)
            unclean = self._shutdown(result.reason)
            if in_main:
                for sig, handler in previous.items():
                    signal.signal(sig, handler)
            self._plan_file.unlink(missing_ok=True)
            if self._recorder is not None:
                self._recorder.join(30.0)  # its taps ended with the processes: it writes the file's index
            stop_logging_to(logged)
        if unclean:
            result.failures.extend(t for t in unclean if t not in result.failures)
            result.exit_code = result.exit_code or 1
            result.reason += f"; {', '.join(unclean)} did not stop in time"
        late = self.failures[failed_before:]
        if late:  # nodes that raised while the graph stopped: logged by their process, and a failure
            result.failures.extend(f for f in late if f not in result.failures)
            result.exit_code = result.exit_code or 1
            result.reason += f"; {', '.join(late)} failed during shutdown"
        return result

    def _supervise(self) -> LaunchResult:
        for target in self.plan.processes():
            self.children[target] = self._spawn(target)
        local_nodes = self.plan.nodes_in(LAUNCHER)
        os.environ.update(self.plan.env_of(LAUNCHER))  # after the children took their own copy
        install_ros_names()  # rclpy and ROS message packages for the nodes written for ROS
        if local_nodes:
            self.host = Host(self.plan, LAUNCHER, self.session, self._local_failure, self.stop,
                             lambda: self.events.put({"event": "local_done"}),
                             lambda node, unheard: self.events.put({"event": "node_done", "node": node,
                                                                    "unheard": unheard}))
            self.control = ControlServer(self.host, session_folder(self.session), LAUNCHER)
        waiting = set(self.children)
        # --duration bounds the whole launch, start-up included (a target may wait on a ROS master); the start-up
        # limit does not count a target's preparation (a simulator compiling its design), which is announced
        limit = self.start_timeout
        patience = limit if self.duration is None else min(limit, self.duration)
        deadline = time.monotonic() + patience
        ends = None if self.duration is None else time.monotonic() + self.duration
        preparing: dict[str, float] = {}
        while waiting:
            now = time.monotonic()
            timeout = min(1.0, ends - now) if preparing and ends is not None else 1.0 if preparing else deadline - now
            event = self._next_event(timeout)
            if event is None:
                if preparing and (ends is None or time.monotonic() < ends):
                    continue
                if (self.duration is not None and self.duration <= limit) or preparing:
                    sys.stderr.write(f"[ERROR] [launch]: --duration {self.duration:g} s passed while target(s) "
                                     f"{', '.join(sorted(waiting))} were still starting; stopping\n")
                    return LaunchResult(1, sorted(waiting), "duration elapsed during start-up")
                raise LaunchError(f"targets {sorted(waiting)} did not start within {limit:g} s (the start-up limit: "
                                  "hetros launch --start-timeout); see their output above for what they wait on")
            if event["event"] == "preparing":
                preparing[f"{event['target']}/{event['node']}"] = time.monotonic()
                log.info("target %s: preparing %s (a simulator compiles the design on its first launch; this does "
                         "not count against the start-up limit)", event["target"], event["node"])
                continue
            if event["event"] == "prepared":
                began = preparing.pop(f"{event['target']}/{event['node']}", time.monotonic())
                deadline += time.monotonic() - began
                if ends is not None:
                    deadline = min(deadline, ends)
                log.info("target %s: %s prepared in %.1f s", event["target"], event["node"], float(event["seconds"]))
                continue
            if event["event"] == "ready":
                waiting.discard(event["target"])
                log.info("target %s ready (pid %s, cpus %s)", event["target"], event["pid"], event["cpus"])
            elif event["event"] == "start_failed":
                self.failures.append(event["target"])
                sys.stderr.write(f"[ERROR] [launch]: target {event['target']} failed to start: "
                                 f"{event['error']}\n{event['traceback']}")
                return LaunchResult(1, self.failures, "start failed")
            elif event["event"] == "exited":
                self.failures.append(event["target"])
                return LaunchResult(1, self.failures, f"target {event['target']} exited during start-up")
            elif event["event"] == "signal":
                return LaunchResult(130, [], "interrupted")
        if self.plan.hosts:
            refused = self._meet_hosts()
            if refused is not None:
                return refused
        if self.record_to is not None:
            self._start_recording(self.record_to)
        for child in self.children.values():
            self._send(child, "go")
        if self.host is not None:
            self.host.start()
        if self.link is not None:
            self.link.announce("running")
        return self._watch()

    def _start_recording(self, out: Path) -> None:
        """``launch --record``: every topic of this machine into ``out`` through taps, as ``hetros record``
        would from another terminal, until the launch stops."""
        from ..observe._bag import record, recordable
        from ..observe._inspect import RunningLaunch

        looking = RunningLaunch.find(session=self.session)
        attached = threading.Event()

        def recorder() -> None:
            try:
                summary = record(looking, recordable(looking, None), out, stop=self.stop, attached=attached.set)
                log.info("%s", summary.describe())
            except Error as exc:
                log.error("recording into %s failed: %s", out, exc)
            finally:
                attached.set()
        self._recorder = threading.Thread(target=recorder, name="recorder", daemon=True)
        self._recorder.start()
        attached.wait(30.0)  # its taps are in place before the first message is published

    def _meet_hosts(self) -> LaunchResult | None:
        """The start barrier across hosts: announce that this host is ready, then wait (for as long
        as it takes, Ctrl-C ends it) until every other host of the project is, with the same hash."""
        self.link = HostLink(self.plan, self.events.put)
        self.link.announce("ready")
        me = self.plan.hosts[self.plan.local_host]
        log.info("host %s (%s) ready; waiting for %s", me.name, me.address, ", ".join(self.link.missing()) or "nobody")
        said = time.monotonic()
        while True:
            if mismatch := self.link.mismatch():
                sys.stderr.write(f"[ERROR] [launch]: {mismatch}\n")
                return LaunchResult(1, [], mismatch)
            missing = self.link.missing()
            if not missing:
                log.info("every host is ready: starting the nodes")
                return None
            if time.monotonic() - said > 5.0:
                log.info("still waiting for host(s) %s", ", ".join(
                    f"{h} ({self.plan.hosts[h].address})" for h in missing))
                said = time.monotonic()
            event = self._next_event(1.0)
            if event is None or event["event"] in ("host_state", "host_back", "host_lost"):
                continue
            if event["event"] == "signal":
                return LaunchResult(130, [], "interrupted while waiting for the other hosts")
            if event["event"] == "exited":
                self.failures.append(event["target"])
                return LaunchResult(1, self.failures, f"target {event['target']} exited during start-up")
            self.events.put(event)  # for the watch loop
            time.sleep(0.01)

    def _peer_news(self, event: dict[str, Any]) -> LaunchResult | None:
        """A host came, went or came back: report it, and act as ``on_peer_lost`` says."""
        assert self.link is not None
        host = event["host"]
        address = self.plan.hosts[host].address
        if mismatch := self.link.mismatch():
            sys.stderr.write(f"[ERROR] [launch]: {mismatch}\n")
            return LaunchResult(1, [host], mismatch)
        if event["event"] == "host_leaving":
            if event["ok"]:
                log.info("host %s (%s) finished (%s)", host, address, event["why"])
            else:
                sys.stderr.write(f"[ERROR] [launch]: host {host} ({address}) stopped: {event['why']}\n")
            if self.plan.on_peer_lost == "stop":
                return LaunchResult(0 if event["ok"] else 1, [] if event["ok"] else [host],
                                    f"host {host} {'finished' if event['ok'] else 'failed'}")
        elif event["event"] == "host_lost":
            if self.plan.on_peer_lost == "stop":
                sys.stderr.write(f"[ERROR] [launch]: host {host} ({address}) is gone; shutting the graph down "
                                 "(on_peer_lost: stop)\n")
                return LaunchResult(1, [host], f"host {host} ({address}) was lost")
            sys.stderr.write(f"[ERROR] [launch]: host {host} ({address}) is gone; its topics pause until it "
                             "returns (on_peer_lost: continue)\n")
        elif event["event"] == "host_back":
            log.info("host %s (%s) is back; its topics resume", host, address)
        sys.stderr.flush()
        return None

    def _next_event(self, timeout: float | None) -> dict[str, Any] | None:
        try:
            return next_item(self.events, timeout)  # a deadline already past takes what is there, at once
        except queue.Empty:
            return None

    def _watch(self) -> LaunchResult:
        end = None if self.duration is None else time.monotonic() + self.duration
        running = set(self.children) | ({LAUNCHER} if self.host else set())
        while running:
            event = self._next_event(None if end is None else end - time.monotonic())
            if event is None:
                return LaunchResult(1 if self.failures else 0, self.failures, "duration elapsed")
            kind = event["event"]
            if kind == "signal":
                return LaunchResult(1 if self.failures else 0, self.failures, "interrupted")
            if kind == "finished":  # something driving the launch from inside (``hetros play --launch``)
                return LaunchResult(1 if self.failures or not event["ok"] else 0, self.failures, event["why"])
            if kind == "node_failed":
                optional = (spec := self.plan.nodes.get(event["node"])) is not None and spec.optional
                what = "restarting it" if event["restarting"] else \
                    "it is optional: the graph goes on" if optional else "shutting the graph down"
                sys.stderr.write(f"[ERROR] [launch]: node {event['node']} (target {event['target']}) "
                                 f"raised; {what}:\n{event['traceback']}")
                sys.stderr.flush()
                if not event["restarting"] and not optional:
                    self.failures.append(event["node"])
                    return LaunchResult(1, self.failures, f"node {event['node']} failed")
            elif kind == "exited":
                child = self.children[event["target"]]
                running.discard(event["target"])
                if child.stopping:
                    continue
                code = event["code"]
                if code != 0:
                    cause = death_cause(code)
                    sys.stderr.write(f"[ERROR] [launch]: target {event['target']} (pid {child.proc.pid}) "
                                     f"died: {cause}; shutting the graph down\n")
                    sys.stderr.flush()
                    self.failures.append(event["target"])
                    nodes = ", ".join(n for n, spec in self.plan.nodes.items() if spec.target == event["target"])
                    return LaunchResult(1, self.failures, f"target {event['target']} died ({cause}; it ran "
                                                          f"node(s) {nodes})")
            elif kind == "local_done":
                running.discard(LAUNCHER)
            elif kind == "node_done" and self.plan.nodes[event["node"]].required:
                return self._required_done(event["node"], event.get("unheard") or [])
            elif kind == "stopped" and event.get("failed"):
                self.failures.extend(event["failed"])
            elif kind in ("host_lost", "host_back", "host_state", "host_leaving"):
                outcome = self._peer_news(event)
                if outcome is not None:
                    self.failures.extend(outcome.failures)
                    return outcome
        return LaunchResult(1 if self.failures else 0, self.failures, "all nodes finished")

    def _required_done(self, node: str, unheard: list[str]) -> LaunchResult:
        """A required node returned: the launch ends, and fails when that node consumed topics and
        never received a message on any of them (its input never came: a result made of nothing)."""
        if not unheard:
            log.info("required node %s finished; shutting the graph down", node)
            return LaunchResult(1 if self.failures else 0, self.failures, f"required node {node} finished")
        why = (f"required node {node} finished without receiving a message on {', '.join(unheard)}: "
               "nothing reached it (check the topics' publishers with `hetros topic info -v`)")
        sys.stderr.write(f"[ERROR] [launch]: {why}\n")
        sys.stderr.flush()
        self.failures.append(node)
        return LaunchResult(1, self.failures, why)

    # -- stop ------------------------------------------------------------------------------

    def _send(self, child: _Child, line: str) -> None:
        try:
            assert child.proc.stdin is not None
            child.proc.stdin.write(line + "\n")
            child.proc.stdin.flush()
        except (BrokenPipeError, OSError, ValueError):
            pass

    def _failed_at_shutdown(self, nodes: Iterable[str]) -> None:
        self.failures.extend(node for node in nodes if node not in self.failures)

    def _shutdown(self, reason: str) -> list[str]:
        """Stop everything in order; return the targets and nodes that had to be abandoned or killed.

        Every process learns why (``Graph.stop_reason``), so a call interrupted by the shutdown
        can say what it was waiting for and what went away.
        """
        reason = " ".join(reason.split())
        if self.host is not None:
            self.host.graph.stop_reason = reason
        self.stop.set()
        # processes with shutdown hooks first (rospy's on_shutdown): what a hook publishes still finds its
        # subscribers running, as under roslaunch, which stops nodes one by one
        hooked = [child for child in self.children.values() if child.hooks]
        for child in hooked:
            child.stopping = True
            self._send(child, f"stop {reason}")
        deadline = time.monotonic() + 5.0
        for child in hooked:
            try:
                child.proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                pass  # killed below with the rest
        for child in self.children.values():
            if not child.hooks:
                child.stopping = True
                self._send(child, f"stop {reason}")
        stuck: list[str] = []
        if self.control is not None:
            self.control.close()
        if self.host is not None:
            stuck = self.host.stop(timeout=5.0)
        deadline = time.monotonic() + 5.0
        for child in self.children.values():
            try:
                child.proc.wait(timeout=max(deadline - time.monotonic(), 0.1))
            except subprocess.TimeoutExpired:
                log.error("target %s did not stop within 5 s; killing it", child.target)
                child.proc.kill()
                child.proc.wait()
                stuck.append(child.target)
            if child.proc.stdin is not None:
                try:
                    child.proc.stdin.close()
                except OSError:
                    pass
            if child.reader is not None:
                child.reader.join(timeout=5.0)  # its last lines are forwarded then (a loaded machine is slow)
        if self.host is not None:
            self._failed_at_shutdown(t.spec.name for t in self.host.threads if t.failed and not t.spec.optional)
        while (event := self._next_event(0)) is not None:
            if event["event"] == "stopped":
                stuck.extend(f"node {node} (target {event['target']})" for node in event.get("stuck", []))
                self._failed_at_shutdown(event.get("failed", []))
        if stuck:
            log.error("%s did not stop within 5 s of shutdown", ", ".join(stuck))
        if self.link is not None:
            self.link.close()
        remove_session_segments(self.session)
        cleanup_stale()
        return stuck


def launch(plan: Plan, *, duration: float | None = None, host: str | None = None,
           record: Path | None = None, start_timeout: float = START_TIMEOUT) -> LaunchResult:
    """Run ``plan`` here; with hosts, this machine's share of it (``host``, else the host whose
    address is this machine's)."""
    if plan.hosts:
        if host is not None and host not in plan.hosts:
            raise LaunchError(f"--as {host}: the project's hosts are {', '.join(plan.hosts)}")
        if host is not None and not is_local_address(plan.hosts[host].address):
            raise LaunchError(
                f"--as {host}: its address {plan.hosts[host].address} is not one of this machine's, so its DDS "
                f"participant cannot use it; run this on {host}'s machine, or change hosts.{host}.address in "
                "the project file to an address of this one")
        plan = plan.on_host(host or local_host(plan))
    elif host is not None:
        raise LaunchError(f"--as {host}: the project names no hosts (add a hosts: section)")
    _check_hardware(plan)
    _check_shared_memory(plan)
    return Launcher(plan, duration=duration, record=record, start_timeout=start_timeout).run()


def _check_shared_memory(plan: Plan) -> None:
    """Refuse, before anything starts, a launch whose shared memory /dev/shm has no room for (a
    full /dev/shm otherwise kills the first publisher that writes with SIGBUS)."""
    needs = [reserved_bytes(plan.channels[edge.channel].qos, None) for edge in plan.edges if edge.transport == "shm"]
    if needs:
        check_room(max(needs), "each shared-memory topic of this launch")


def _check_hardware(plan: Plan) -> None:
    """Refuse, before anything starts, a launch whose fpga targets could not run: a node there without a
    hardware implementation, or no simulator on this machine."""
    bare = sorted(n for n in plan.nodes if plan.in_hardware(n) and not plan.nodes[n].hw)
    if bare:
        raise LaunchError(f"node(s) {', '.join(bare)} sit on fpga targets without a hardware implementation, so "
                          "nothing can run them: give each a hw: (module:Component, see hetros.hw.nodes) or move "
                          "it to a process target (`hetros hw build` generates topic networks without one)")
    verilated = sorted({plan.nodes[n].target for n in plan.nodes if plan.in_hardware(n)
                        and (not plan.hosts or plan.host_of(n) == plan.local_host)
                        and plan.targets[plan.nodes[n].target].sim == "verilator"})
    if verilated and shutil.which("verilator") is None:
        raise LaunchError(f"fpga target(s) {', '.join(verilated)} run in Verilator, which this machine lacks: install "
                          "Debian's verilator package (`make install-test` does, as root), or set sim: amaranth on a "
                          "small design")
