"""Service introspection (``runtime._service_events``): a call's four events reach a look at
``<service>/_service_event`` in order, with the request or response; METADATA strips them, OFF makes
none, and with nobody looking no event is made at all."""

from __future__ import annotations

import threading
from collections.abc import Iterator

import pytest

from hetros import Node
from hetros.interfaces.example_interfaces.srv import AddTwoInts
from hetros.msg import registry
from hetros.runtime import EVENT_TOPIC_SUFFIX, EventKind, Graph, Introspection, TapSink, client_gid
from hetros.transport import MessageCodec

EVENT = "example_interfaces/srv/AddTwoInts_Event"


@pytest.fixture
def graph() -> Iterator[Graph]:
    graph = Graph.standalone()
    yield graph
    graph.shutdown()


def _calls(graph: Graph, count: int, *, server_state: Introspection | None = None,
           client_state: Introspection | None = None, look: bool = True) -> tuple[list[object], int]:
    server, caller = Node("server", graph), Node("caller", graph)
    service = server.create_service(AddTwoInts, "/add", lambda r: AddTwoInts.Response(sum=r.a + r.b))
    client = caller.create_client(AddTwoInts, "/add")
    if server_state is not None:
        service.events.state = server_state
    if client_state is not None:
        client.events.state = client_state
    point = graph.taps()["/add" + EVENT_TOPIC_SUFFIX]
    codec = MessageCodec(registry(), EVENT)
    sink = TapSink(codec, data=True)
    if look:
        point.attach(sink)
    stop = threading.Event()
    spinner = threading.Thread(target=lambda: [server.spin_once(0.05) for _ in iter(stop.is_set, True)])
    spinner.start()
    try:
        for i in range(count):
            assert client.call(AddTwoInts.Request(a=i, b=10), timeout=5.0).sum == i + 10
    finally:
        stop.set()
        spinner.join()
    events = []
    while (taken := sink.take(0.0)) is not None:
        events.append(codec.decode(memoryview(taken[1])))
    return events, point.published


def test_each_call_gives_its_four_events_in_order_with_request_and_response(graph: Graph) -> None:
    events, _ = _calls(graph, 2)
    kinds = [EventKind(e.info.event_type) for e in events]  # type: ignore[attr-defined]
    assert kinds == [EventKind.REQUEST_SENT, EventKind.REQUEST_RECEIVED, EventKind.RESPONSE_SENT,
                     EventKind.RESPONSE_RECEIVED] * 2
    assert [e.info.sequence_number for e in events] == [1] * 4 + [2] * 4  # type: ignore[attr-defined]
    assert all(bytes(e.info.client_gid) == client_gid("caller") for e in events)  # type: ignore[attr-defined]
    first = events[:4]
    assert [(list(e.request), list(e.response)) for e in first] == [  # type: ignore[attr-defined]
        ([AddTwoInts.Request(a=0, b=10)], []), ([AddTwoInts.Request(a=0, b=10)], []),
        ([], [AddTwoInts.Response(sum=10)]), ([], [AddTwoInts.Response(sum=10)])]


def test_metadata_strips_contents_and_off_makes_no_event(graph: Graph) -> None:
    events, _ = _calls(graph, 1, server_state=Introspection.METADATA, client_state=Introspection.OFF)
    assert [EventKind(e.info.event_type) for e in events] == [  # type: ignore[attr-defined]
        EventKind.REQUEST_RECEIVED, EventKind.RESPONSE_SENT]
    assert all(len(e.request) == len(e.response) == 0 for e in events)  # type: ignore[attr-defined]


def test_nobody_looking_makes_no_event(graph: Graph) -> None:
    events, published = _calls(graph, 3, look=False)
    assert events == [] and published == 0


def test_a_service_event_type_is_rosidls(graph: Graph) -> None:
    """``<srv>_Event``: ServiceEventInfo, and the request or the response, at most one of each."""
    fields = registry().fielddefs[registry().service_event("example_interfaces/srv/AddTwoInts").__msgtype__][1]
    assert [name for name, _ in fields] == ["info", "request", "response"]
    assert registry().service_event("example_interfaces/srv/AddTwoInts").__msgtype__ == EVENT
