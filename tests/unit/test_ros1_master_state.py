"""The master's bookkeeping, call by call (the calls out to nodes are recorded, not made)."""

from __future__ import annotations

from typing import Any

import pytest

from hetros.transport.tcpros import MasterState


@pytest.fixture
def state() -> tuple[MasterState, list[tuple[str, str, tuple[Any, ...]]]]:
    calls: list[tuple[str, str, tuple[Any, ...]]] = []
    return MasterState("http://127.0.0.1:11311/", lambda api, method, args: calls.append((api, method, args))), calls


def test_subscribers_learn_of_publishers_both_ways(state: Any) -> None:
    master, calls = state
    assert master.registerSubscriber("/b", "/t", "std_msgs/String", "http://b/") == (1, "Subscribed to [/t]", [])
    code, _, subscribers = master.registerPublisher("/a", "/t", "std_msgs/String", "http://a/")
    assert (code, subscribers) == (1, ["http://b/"])
    assert calls == [("http://b/", "publisherUpdate", ("/master", "/t", ["http://a/"]))]
    assert master.registerSubscriber("/c", "/t", "*", "http://c/")[2] == ["http://a/"]
    assert master.unregisterPublisher("/a", "/t", "http://other/")[2] == 0  # not that registration
    assert master.unregisterPublisher("/a", "/t", "http://a/")[2] == 1
    assert calls[-1] == ("http://c/", "publisherUpdate", ("/master", "/t", []))
    assert master.getTopicTypes("/x")[2] == [["/t", "std_msgs/String"]]


def test_system_state_services_and_nodes(state: Any) -> None:
    master, _calls = state
    master.registerPublisher("/a", "/t", "std_msgs/String", "http://a/")
    master.registerService("/a", "/srv", "rosrpc://a:1", "http://a/")
    assert master.getSystemState("/x")[2] == [[["/t", ["/a"]]], [], [["/srv", ["/a"]]]]
    assert master.lookupService("/x", "/srv")[2] == "rosrpc://a:1"
    assert master.lookupService("/x", "/none")[0] == -1
    assert master.lookupNode("/x", "/a")[2] == "http://a/"
    assert master.lookupNode("/x", "/ghost") == (-1, "unknown node [/ghost]", "")


def test_a_node_registered_again_replaces_the_old_one(state: Any) -> None:
    master, calls = state
    master.registerPublisher("/a", "/t", "std_msgs/String", "http://old/")
    master.registerSubscriber("/a", "/u", "std_msgs/String", "http://new/")
    assert ("http://old/", "shutdown") == calls[-1][:2]
    assert master.getSystemState("/x")[2][0] == []  # the old process' publication is gone


def test_parameters_resolve_search_and_notify(state: Any) -> None:
    master, calls = state
    assert master.setParam("/ns/node", "gain", 2.5)[0] == 1  # relative to the caller's namespace
    assert master.getParam("/x", "/ns/gain") == (1, "Parameter [/ns/gain]", 2.5)
    assert master.getParam("/x", "/missing")[0] == -1
    master.setParam("/x", "/robot", {"arm": {"joints": 6}, "name": "r2"})
    assert master.getParam("/x", "/robot/arm/joints")[2] == 6
    assert sorted(master.getParamNames("/x")[2]) == ["/ns/gain", "/robot/arm/joints", "/robot/name"]
    assert master.searchParam("/robot/arm/driver", "name") == (1, "Found [/robot/name]", "/robot/name")
    assert master.searchParam("/a/b/c", "nothing")[0] == -1
    assert master.subscribeParam("/n", "http://n/", "/robot/arm")[2] == {"joints": 6}
    master.setParam("/x", "/robot/arm/joints", 7)
    assert calls[-1] == ("http://n/", "paramUpdate", ("/master", "/robot/arm/", {"joints": 7}))
    assert master.deleteParam("/x", "/robot/arm")[0] == 1
    assert calls[-1] == ("http://n/", "paramUpdate", ("/master", "/robot/arm/", {}))
    assert master.hasParam("/x", "/robot/arm")[2] is False
    assert master.deleteParam("/x", "/robot/arm")[0] == -1
    assert master.unsubscribeParam("/n", "http://n/", "/robot/arm")[2] == 1


def test_calls_with_wrong_arguments_are_refused_before_they_reach_the_state() -> None:
    import xmlrpc.client

    from hetros.transport.tcpros import Master

    master = Master("127.0.0.1", 0)
    try:
        api = xmlrpc.client.ServerProxy(master.uri, allow_none=True)
        assert api.registerPublisher("/n", None, "std_msgs/String", "http://127.0.0.1:1/")[:2] == \
            [-1, "registerPublisher: topic must be a string, not NoneType"]
        assert api.registerPublisher("/n", 7, "std_msgs/String", "http://127.0.0.1:1/")[0] == -1
        assert api.registerPublisher("/n")[0] == -1  # too few arguments
        with pytest.raises(xmlrpc.client.Fault, match="not supported"):
            api._forget("/n")
        assert api.getSystemState("/n") == [1, "current system state", [[], [], []]]
    finally:
        master.close()


@pytest.mark.parametrize(("value", "refused"), [
    ("deep", "nests deeper than 64 levels"),
    ("wide", "holds more than 1,000,000 values"),
    ("big", "holds more than 64 MiB"),
])
def test_a_parameter_beyond_the_bounds_is_refused_and_the_tree_stays_readable(state: Any, value: str,
                                                                              refused: str) -> None:
    master, _calls = state
    master.setParam("/a", "/keep", 1)
    nested: Any = 1
    if value == "deep":
        for _ in range(100_000):
            nested = [nested]
    elif value == "wide":
        nested = list(range(1_000_001))
    else:
        nested = "x" * (65 << 20)
    code, message, _ = master.setParam("/a", "/evil", nested)
    assert code == -1 and refused in message
    assert master.getParam("/b", "/")[2] == {"keep": 1}
    assert master.setParam("/a", "/ok", [[[1]]])[0] == 1


def test_a_deep_parameter_sent_over_xmlrpc_breaks_nothing_for_others() -> None:
    """As an attacker sends it: 100,000 nested arrays in one XML-RPC request to `hetros master`."""
    import http.client
    import xmlrpc.client

    from tests.support.ros1 import ros1_master

    for uri, _env in ros1_master("hetros"):
        body = ("<?xml version='1.0'?><methodCall><methodName>setParam</methodName><params>"
                "<param><value><string>/evil</string></value></param>"
                "<param><value><string>/deep</string></value></param><param>"
                + "<value><array><data>" * 100_000 + "<value><int>1</int></value>"
                + "</data></array></value>" * 100_000 + "</param></params></methodCall>")
        host = uri.split("//")[1].rstrip("/")
        connection = http.client.HTTPConnection(host, timeout=60)
        connection.request("POST", "/RPC2", body.encode(), {"Content-Type": "text/xml"})
        connection.getresponse().read()
        master = xmlrpc.client.ServerProxy(uri)
        assert master.setParam("/good", "/fine", 7)[0] == 1
        code, _, tree = master.getParam("/other", "/")
        assert code == 1 and tree.get("fine") == 7 and "deep" not in tree
