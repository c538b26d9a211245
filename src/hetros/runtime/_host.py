"""Runs the nodes of one process, one thread per node, and reports their failures."""

from __future__ import annotations

import importlib
import importlib.util
import inspect
import runpy
import sys
import threading
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .._errors import LaunchError, NodeError, ShutdownError
from .._log import get_logger
from ..msg import registry
from ..plan import NodePlan, Plan
from ._argv import node_argv, set_node_argv
from ._graph import Graph
from ._log import node_logger
from ._node import Node
from ._ros_main import ros_main, runs_as_ros_main

log = get_logger("hetros.launch")

FailureReport = Callable[[str, str, bool], None]
DoneReport = Callable[[str, list[str]], None]  # node, what it never heard (Node.unheard)


def resolve(run: str, root: str, args: tuple[str, ...] = ()) -> Callable[..., Any]:
    """``module:object``, looked up next to the project file first, then in the environment; or a
    script's path (no ``:``), run as ``__main__`` with ``args`` as its command line."""
    if ":" not in run:
        return script_main(Path(root) / run, args)
    module_name, _, attr = run.partition(":")
    if root and root not in sys.path:
        sys.path.insert(0, root)
    try:
        with node_argv([_module_file(module_name), *args]):
            module = importlib.import_module(module_name)
    except ImportError as exc:
        raise LaunchError(f"cannot import {module_name!r} for run: {run!r}: {exc}") from exc
    try:
        target: Callable[..., Any] = getattr(module, attr)
    except AttributeError:
        raise LaunchError(f"module {module_name!r} has no {attr!r} (run: {run!r})") from None
    return target


def script_main(path: Path, args: tuple[str, ...]) -> Callable[[], None]:
    """A script as a ROS main(): run as ``__main__`` (a ROS 1 node's script keeps its logic under
    ``if __name__ == "__main__":``), ``sys.argv`` its path and ``args`` (this node's own, ``_argv``)."""
    if not path.is_file():
        raise LaunchError(f"run: {path} is not a file: give a script's path relative to the project file, or "
                          "module:function")

    def main() -> None:
        set_node_argv([str(path), *args])
        try:
            runpy.run_path(str(path), run_name="__main__")
        except SystemExit as exit_:
            if exit_.code not in (None, 0):
                raise NodeError(f"script {path.name} exited with {exit_.code!r}") from None
    main.__qualname__ = main.__name__ = path.name
    return main


def _module_file(module_name: str) -> str:
    """The file ``module_name`` would be imported from (its name when that cannot be told without importing
    it): what a console script's ``sys.argv[0]`` is, while the module is imported."""
    loaded = sys.modules.get(module_name)
    if loaded is not None:
        return str(getattr(loaded, "__file__", None) or module_name)
    try:
        spec = importlib.util.find_spec(module_name)
    except (ImportError, ValueError):
        return module_name
    return str(spec.origin) if spec is not None and spec.origin else module_name


def _program(run: str, body: Callable[..., Any]) -> str:
    """``sys.argv[0]`` of a node: its script, or the file of the module its ``run:`` names (a console
    script's argv[0] is its own file too)."""
    if ":" not in run:
        return run
    module = sys.modules.get(run.partition(":")[0])
    return str(getattr(module, "__file__", None) or getattr(body, "__module__", run))


def _give_thread_an_event_loop() -> Any:
    """A node's main() runs in a thread of its own, where asyncio has no loop: ROS code that calls
    ``asyncio.get_event_loop()`` (ros2/examples' client_asyncio) gets one, as in a process's main thread.
    Only where the node's module imported asyncio: a worker that never uses it does not pay for it (it maps
    OpenSSL) nor for the loop's two file descriptors per node."""
    asyncio = sys.modules.get("asyncio")
    if asyncio is None:
        return None
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        return loop  # closed when the node ends
    return None


def run_node_body(factory: Callable[..., Any], node: Node) -> None:
    """Call a node function or construct a node class; spin when it left callbacks behind
    that it never spun itself (one that ran its own spin loop and returned is done). A ROS
    ``main()`` (no argument) runs with the node bound to this thread (``_ros_main``), and so does a ROS node
    class loaded as a component (one offering ``run_as_component``, as rclpy's ``Node`` does)."""
    if inspect.isclass(factory) and callable(component := getattr(factory, "run_as_component", None)):
        factory = component
    if runs_as_ros_main(factory):
        with ros_main(node):
            try:
                factory()
            except SystemExit as exit_:  # sys.exit() in a main() ends its node, not the process
                if exit_.code in (None, 0):
                    return
                if node.graph.stop.is_set():
                    raise ShutdownError(f"main() exited with {exit_.code!r} as the graph stopped") from None
                raise NodeError(f"main() exited with {exit_.code!r}") from None
        return
    result = factory(node)
    if inspect.isclass(factory) and hasattr(result, "run"):
        result.run()
    if node.executor.entities and not node.spun and node.ok():
        node.spin()


def _user_frame(exc: BaseException) -> str:
    """``file:line`` of the innermost frame of ``exc``'s traceback outside hetros itself."""
    package = str(Path(__file__).resolve().parent.parent)
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if not f.filename.startswith(package)]
    return f"{frames[-1].filename}:{frames[-1].lineno}" if frames else "inside hetros"


class NodeThread:
    """One node in its own thread, restarted per its ``restart`` policy."""

    def __init__(self, spec: NodePlan, graph: Graph, on_failure: FailureReport,
                 on_exit: Callable[[], None], on_done: DoneReport) -> None:
        self.on_exit = on_exit
        self.on_done = on_done
        self.spec = spec
        self.graph = graph
        self.on_failure = on_failure
        self.failed = False
        self.thread = threading.Thread(target=self._main, name=f"node:{spec.name}", daemon=True)

    def start(self) -> None:
        self.thread.start()

    def _main(self) -> None:
        try:
            self._run()
        finally:
            self.on_exit()

    def _run(self) -> None:
        restarts = 0
        plan = self.graph.plan
        root = plan.root if plan else ""
        while not self.graph.stop.is_set():
            node = Node(self.spec.name, self.graph)
            finished = False
            loop: Any = None
            try:
                body = resolve(self.spec.run, self.spec.root or root, self.spec.args)
                set_node_argv([_program(self.spec.run, body), *self.spec.args])
                loop = _give_thread_an_event_loop()
                run_node_body(body, node)
                if node.thread_failure is not None:
                    raise NodeError(f"a thread node {self.spec.name} started raised (its traceback is logged "
                                    f"above):\n{node.thread_failure}")
                finished = True
                if not self.graph.stop.is_set():
                    self.on_done(self.spec.name, node.unheard())
                return
            except ShutdownError as exc:
                if self.graph.stop.is_set():
                    # a blocking call ended by the shutdown: say where, since the code after it did not run
                    log.info("node %s ended at shutdown (%s): %s", self.spec.name, _user_frame(exc), exc)
                return
            except BaseException:
                if self.graph.stop.is_set():
                    # the graph was stopping, but a node that raises is still a failure: never swallowed
                    self.failed = True
                    log.error("node %s raised during shutdown:\n%s", self.spec.name, traceback.format_exc())
                    return
                restart = self.spec.restart == "on-failure" and restarts < self.spec.max_restarts
                self.on_failure(self.spec.name, traceback.format_exc(), restart)
                if not restart:
                    self.failed = True
                    node.failing = True
                    return
                restarts += 1
                node_logger(self.spec.name).warning(
                    "restarting (restart: on-failure, %d of %d)", restarts, self.spec.max_restarts
                )
                self.graph.stop.wait(min(0.2 * 2**restarts, 2.0))
            finally:
                if loop is not None and not loop.is_running() and not loop.is_closed():
                    loop.close()
                node.report_times()
                node.close()
                if finished:  # done for good: its FIFOs, kept for a restart, hold back no publisher now
                    self.graph.forget(self.spec.name)


class Host:
    """All nodes the plan puts in one process."""

    def __init__(self, plan: Plan, process: str, session: str, on_failure: FailureReport,
                 stop: threading.Event | None = None,
                 on_all_exited: Callable[[], None] = lambda: None,
                 on_done: DoneReport = lambda node, unheard: None,
                 on_preparing: Callable[[str, float | None], None] = lambda node, seconds: None) -> None:
        """``on_preparing(node, None)`` before a node's start-up work (a simulator's compilation) and
        ``on_preparing(node, seconds)`` after it: the launcher does not count it against its start-up limit."""
        self._running = 0
        # what this process' reliable writers could not deliver before it ended (``Graph.linger``)
        self.unacknowledged: list[str] = []
        self._count_lock = threading.Lock()
        self._on_all_exited = on_all_exited
        for folder in reversed(plan.python_path):
            if folder not in sys.path:
                sys.path.insert(0, folder)
        types = registry()
        for folder in plan.message_paths:
            types.load_folder(Path(folder))
        self.graph = Graph(plan, process, session, stop, types)
        self.threads = [NodeThread(plan.nodes[n], self.graph, on_failure, self._exited, on_done)
                        for n in plan.nodes_in(process)]
        for nthread in self.threads:
            function = resolve(nthread.spec.run, nthread.spec.root or plan.root, nthread.spec.args)
            prepare = getattr(function, "prepare", None)
            if callable(prepare):
                # start-up work that must not count against the graph's time (a simulator's
                # compilation): done before this process reports ready, so before any node runs
                on_preparing(nthread.spec.name, None)
                started = time.perf_counter()
                prepare(plan, nthread.spec.name, types)
                on_preparing(nthread.spec.name, time.perf_counter() - started)
        self.graph.prepare(plan.nodes_in(process))

    def _exited(self) -> None:
        with self._count_lock:
            self._running -= 1
            done = self._running == 0
        if done:
            if not self.graph.stop.is_set():
                # every node returned: what they published reliably must reach its subscribers first
                self.unacknowledged = self.graph.linger()
                for line in self.unacknowledged:
                    log.error("%s", line)
            self._on_all_exited()

    def start(self) -> None:
        self.graph.wait_for_remote_readers()
        self._running = len(self.threads)
        for nthread in self.threads:
            nthread.start()
        if not self.threads:
            self._on_all_exited()

    def alive(self) -> bool:
        return any(t.thread.is_alive() for t in self.threads)

    def stop(self, timeout: float = 5.0) -> list[str]:
        """Stop every node; return the names of nodes that did not finish in time."""
        self.graph.shutdown()
        stuck = []
        for nthread in self.threads:
            if nthread.thread.ident is None:
                continue  # stopped before it started (Ctrl-C during start-up)
            nthread.thread.join(timeout)
            if nthread.thread.is_alive():
                stuck.append(nthread.spec.name)
        self.graph.close()
        return stuck
