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


def loopback_peer_uid(peer: tuple[str, int], local_port: int) -> int | None:
    """The account owning the other end of a loopback TCP connection to ``local_port`` from ``peer``
    (its address and port), read from the kernel's socket table (/proc/net/tcp, tcp6); None when it is
    not found (not loopback, or already gone). A loopback port is open to every account of the machine:
    this is how a server that should serve only its owner tells them apart."""
    import ipaddress

    try:
        address = ipaddress.ip_address(peer[0])
    except ValueError:
        return None
    if not address.is_loopback and not (isinstance(address, ipaddress.IPv6Address) and address.ipv4_mapped and
                                        address.ipv4_mapped.is_loopback):
        return None
    wanted_port, server_port = f"{peer[1]:04X}", f"{local_port:04X}"
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        try:
            with open(table, encoding="ascii") as handle:
                lines = handle.read().splitlines()[1:]
        except OSError:
            continue
        for line in lines:
            fields = line.split()
            if len(fields) < 8:
                continue
            local, remote, uid = fields[1], fields[2], fields[7]
            if local.endswith(f":{wanted_port}") and remote.endswith(f":{server_port}") and uid.isdigit():
                return int(uid)
    return None

