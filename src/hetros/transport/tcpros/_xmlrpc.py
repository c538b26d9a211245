"""XML-RPC as ROS 1 uses it: a threaded server that logs quietly, a client that cannot hang."""

from __future__ import annotations

import logging
import xmlrpc.client
from socketserver import ThreadingMixIn
from typing import Any
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

log = logging.getLogger("hetros.ros1")

CALL_TIMEOUT = 5.0


class _Threaded(ThreadingMixIn, SimpleXMLRPCServer):
    daemon_threads = True
    allow_reuse_address = True


class _Quiet(SimpleXMLRPCRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        log.debug(format, *args)


def serve(host: str, port: int, api: object | None = None) -> SimpleXMLRPCServer:
    """A server for ``api``'s public methods (one thread per request; the caller runs serve_forever).

    Raises OSError when the address cannot be bound."""
    server = _Threaded((host, port), requestHandler=_Quiet, allow_none=True, logRequests=False)
    if api is not None:
        server.register_instance(api)
    return server


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
