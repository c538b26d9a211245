"""XML-RPC as ROS 1 uses it: a threaded server that logs quietly, a client that cannot hang."""

from __future__ import annotations

import inspect
import sys
import threading
import xmlrpc.client
from socketserver import ThreadingMixIn
from typing import Any
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

from ..._log import get_logger
from ._admission import Admission

log = get_logger("hetros.ros1")

CALL_TIMEOUT = 5.0


# no ROS 1 call comes near this; a larger (or unparseable) Content-Length is refused before reading
MAX_BODY = 32 << 20
# requests served at once; a connection beyond them waits a second for a slot, then is closed
MAX_CONCURRENT = 64
# connections still sending their request: the oldest is closed to admit one more (slowloris)
MAX_HALF_OPEN = 32
# a request whose headers and body do not arrive within this, in all, is dropped (slowloris)
REQUEST_TIMEOUT = 10.0


class _Threaded(ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    allow_reuse_address = True

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.admission = Admission("XML-RPC server", MAX_HALF_OPEN, REQUEST_TIMEOUT)  # closed if binding fails
        super().__init__(*args, **kwargs)
        self._slots = threading.BoundedSemaphore(MAX_CONCURRENT)
        self.admission.what = "XML-RPC server at {}:{}".format(*map(str, self.server_address[:2]))

    def process_request(self, request: Any, client_address: Any) -> None:
        """One thread per request, at most ``MAX_CONCURRENT`` at once, at most ``MAX_HALF_OPEN``
        of them still reading their request."""
        if not self._slots.acquire(timeout=1.0):
            log.warning("XML-RPC server at %s:%s busy with %d requests; dropped a connection from %s",
                        *self.server_address[:2], MAX_CONCURRENT, client_address)
            self.shutdown_request(request)
            return
        self.admission.enter(request, f"{client_address[0]}:{client_address[1]}")
        threading.Thread(target=self._serve_one, args=(request, client_address), daemon=True,
                         name="hetros-xmlrpc").start()

    def _serve_one(self, request: Any, client_address: Any) -> None:
        try:
            self.process_request_thread(request, client_address)
        finally:
            self.admission.leave(request)
            self._slots.release()

    def server_close(self) -> None:
        self.admission.close()
        super().server_close()

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A caller that left before its answer (a refused or fuzzed request, a killed node) is one
        line, not socketserver's traceback on stderr; anything else is logged with its traceback."""
        error = sys.exc_info()[1]
        if isinstance(error, ConnectionError | TimeoutError):
            log.info("XML-RPC caller %s:%s left before its answer (%s)", *client_address[:2], error)
        else:
            log.exception("XML-RPC request from %s:%s failed", *client_address[:2])


class _Quiet(SimpleXMLRPCRequestHandler):
    timeout = REQUEST_TIMEOUT

    def decode_request_content(self, data: bytes) -> bytes | None:
        """The whole request has arrived: it no longer counts against the slow-request limits."""
        server = self.server
        if isinstance(server, _Threaded):
            server.admission.leave(self.connection)
        return super().decode_request_content(data)

    def do_POST(self) -> None:
        """Refuse a body that is too large or whose length is not a number before reading any of it."""
        length = self.headers.get("content-length", "")
        if not (length.isdigit() and int(length) <= MAX_BODY):
            log.info("XML-RPC request from %s refused: Content-Length %r (must be 0..%d)", self.client_address,
                     length, MAX_BODY)
            self.send_error(413 if length.isdigit() else 411, "Content-Length must be a number up to "
                                                              f"{MAX_BODY} bytes")
            self.close_connection = True
            return
        super().do_POST()

    def log_message(self, format: str, *args: Any) -> None:
        log.debug(format, *args)


def serve(host: str, port: int, api: object | None = None) -> SimpleXMLRPCServer:
    """A server for ``api``'s public methods (one thread per request; the caller runs serve_forever).

    Raises OSError when the address cannot be bound."""
    server = _Threaded((host, port), requestHandler=_Quiet, allow_none=True, logRequests=False)
    if api is not None:
        register(server, api)
    return server


def register(server: SimpleXMLRPCServer, api: object) -> None:
    """Serve ``api``'s public methods, each call checked against the method's signature first,
    and ``system.multicall`` over them (rospy unregisters that way at shutdown)."""
    server.register_instance(_Checked(api))
    server.register_multicall_functions()


class _Checked:
    """Calls reach the API only with the arguments its signature names, strings where it says ``str``
    and lists where it says ``list``: a wrong call is answered with ROS 1's error code (-1) and never
    reaches (or corrupts) the state behind the API."""

    def __init__(self, api: object) -> None:
        self._api = api

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        function = None if method.startswith("_") else getattr(self._api, method, None)
        if not callable(function):
            raise xmlrpc.client.Fault(1, f"method {method!r} is not supported")
        try:
            bound = inspect.signature(function).bind(*params)
        except TypeError as exc:
            return -1, f"{method}: {exc}", 0
        for name, value in bound.arguments.items():
            expected = str(function.__annotations__.get(name, ""))
            if expected == "str" and not isinstance(value, str):
                return -1, f"{method}: {name} must be a string, not {type(value).__name__}", 0
            if expected.startswith("list") and not isinstance(value, list):
                return -1, f"{method}: {name} must be a list, not {type(value).__name__}", 0
            if expected == "list[str]" and not all(isinstance(item, str) for item in value):
                bad = next(item for item in value if not isinstance(item, str))
                return -1, f"{method}: {name} must be a list of strings, not one holding {bad!r}", 0
        return function(*params)


class _TimedTransport(xmlrpc.client.Transport):
    """xmlrpc.client with a timeout per connection (its default waits forever)."""

    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: Any) -> Any:
        connection = super().make_connection(host)
        connection.timeout = self._timeout
        return connection


def proxy(uri: str, timeout: float = CALL_TIMEOUT) -> Any:
    return xmlrpc.client.ServerProxy(uri, transport=_TimedTransport(timeout), allow_none=True)
