"""Whether an address belongs to this machine: the question behind every "which host am I" and
"can this interface be used" answer, asked the one way that cannot be fooled by a name."""

from __future__ import annotations

import socket


def is_local_address(address: str) -> bool:
    """Whether ``address`` (an IP address or a host name) is one of this machine's: only such an
    address can be bound."""
    try:
        resolved = socket.gethostbyname(address)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
            probe.bind((resolved, 0))
    except OSError:
        return False
    return True
