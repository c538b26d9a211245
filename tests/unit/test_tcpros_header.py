"""TCPROS connection headers: annotated bytes, round trips, and what garbage gets."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from hetros import ProtocolError
from hetros.transport.tcpros._header import MAX_HEADER, decode_header, encode_header, header_length, require


def test_fields_encode_as_annotated() -> None:
    data = encode_header({"callerid": "/listener", "topic": "/chatter"})
    assert data == (
        struct.pack("<I", 4 + 18 + 4 + 14)       # 0  length of what follows
        + struct.pack("<I", 18) + b"callerid=/listener"  # 4
        + struct.pack("<I", 14) + b"topic=/chatter"      # 26
    )
    assert header_length(data[:4], "peer") == len(data) - 4
    assert decode_header(data[4:], "peer") == {"callerid": "/listener", "topic": "/chatter"}


def test_values_keep_equals_signs_newlines_and_emptiness() -> None:
    fields = {"message_definition": "string data\n# a=b\n", "error": "", "md5sum": "*"}
    data = encode_header(fields)
    assert decode_header(data[4:], "peer") == fields


@pytest.mark.parametrize(("body", "expected"), [
    (b"\x05\x00\x00\x00ab", r"peer: connection header field at offset 4 claims 5 bytes, but the header ends 2"),
    (b"\x03\x00\x00\x00abc", r"field at offset 4 is not name=value: b'abc'"),
    (b"\x02\x00\x00\x00=x", r"field at offset 4 is not name=value"),
    (b"\x03\x00\x00\x00a=b\x03\x00\x00\x00a=c", r"field 'a' at offset 11 appears twice"),
    (b"\x03\x00\x00\x00a=b\x01\x00", r"field at offset 11 is cut off \(2 of its 4 length bytes\)"),
    (b"\x03\x00\x00\x00\xff=b", r"field at offset 4 is not UTF-8"),
])
def test_malformed_headers_name_the_offset(body: bytes, expected: str) -> None:
    with pytest.raises(ProtocolError, match=expected):
        decode_header(body, "peer")


def test_an_absurd_length_is_refused_before_any_allocation() -> None:
    with pytest.raises(ProtocolError, match=r"announces 4294967295 bytes \(more than 1048576\)"):
        header_length(b"\xff\xff\xff\xff", "peer")
    assert header_length(struct.pack("<I", MAX_HEADER), "peer") == MAX_HEADER


def test_missing_fields_are_named_with_the_peers_error() -> None:
    with pytest.raises(ProtocolError, match=r"lacks md5sum, type \(it has callerid, error\); it says: no such topic"):
        require({"callerid": "/a", "error": "no such topic"}, ("callerid", "md5sum", "type"), "peer")


@settings(max_examples=2000, deadline=None, derandomize=True, database=None)
@given(st.binary(max_size=64))
def test_any_bytes_decode_or_get_a_protocol_error(body: bytes) -> None:
    try:
        decode_header(body, "peer")
    except ProtocolError:
        pass


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(st.dictionaries(st.text(min_size=1).filter(lambda n: "=" not in n), st.text(), max_size=6))
def test_round_trip(fields: dict[str, str]) -> None:
    data = encode_header(fields)
    assert decode_header(data[4:], "peer") == fields
