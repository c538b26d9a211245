"""The hosts of one graph find each other, start together and notice when one goes away.

Each host's launcher announces itself on ``hetros/<project>/hosts`` (one latched sample
per host: its project hash and its phase) with a DDS liveliness lease, so:

- a host whose project file or message definitions differ is refused, naming both hashes;
- the start barrier: no host lets its nodes run before every host has opened its
  readers and writers (phase ``ready``);
- a host that vanishes (killed, unplugged) is reported by the others within a second,
  and a host that comes back is seen again; the project's ``on_peer_lost`` decides;
- a host that ends in order says so first (phase ``leaving``, whether it ended well and
  why), so the others end in order too instead of reporting a lost host.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable
from typing import Any

from cyclonedds.core import InstanceState, Policy, Qos
from cyclonedds.idl import make_idl_struct
from cyclonedds.pub import DataWriter
from cyclonedds.sub import DataReader
from cyclonedds.util import duration

from ..._errors import LaunchError
from ..._log import get_logger
from ..._net import is_local_address
from ...plan import Plan
from ...transport.dds import HOST_LEASE, DdsDomain

log = get_logger("hetros.hosts")

# how long a host's silence means it is gone (its launcher renews this lease automatically)
LIVELINESS = 0.5


# one instance per host (keyed by its name), so the others learn which host went away
HostState: Any = make_idl_struct("HostState", "hetros::dds_::HostState_", {"host": str, "state": str},
                            field_annotations={"host": {"key": True}})


def local_host(plan: Plan) -> str:
    """The host of ``plan`` whose address belongs to this machine (exactly one must)."""
    mine = [name for name, host in plan.hosts.items() if is_local_address(host.address)]
    if len(mine) != 1:
        listed = ", ".join(f"{n} ({h.address})" for n, h in plan.hosts.items())
        found = f"it is {' and '.join(mine)}" if mine else "none of its addresses is one of them"
        raise LaunchError(f"which host is this machine? The project's hosts are {listed}, and {found}; "
                          "say it with --as <host>")
    return mine[0]


class HostLink:
    """This host's presence among the others. ``on_change`` gets an event (``host_state``,
    ``host_lost``, ``host_back``) on the participant's waiting thread after any host's news; the
    launcher then reads :meth:`missing` and :meth:`mismatch`."""

    def __init__(self, plan: Plan, on_change: Callable[[dict[str, Any]], None]) -> None:
        self.plan = plan
        self.me = plan.local_host
        self._on_change = on_change
        self._lock = threading.Lock()
        self._states: dict[str, dict[str, Any]] = {}
        self._gone: set[str] = set()
        hosts = plan.hosts
        self._domain = DdsDomain(plan.dds_domain, interface=hosts[self.me].address,
                                 peers=[h.address for h in hosts.values()], lease=HOST_LEASE,
                                 configured_at=f"hosts.{self.me}.address")
        qos = Qos(Policy.Reliability.Reliable(max_blocking_time=duration(seconds=1)),
                  Policy.Durability.TransientLocal, Policy.History.KeepLast(1),
                  Policy.Liveliness.Automatic(lease_duration=duration(seconds=LIVELINESS)))
        topic = self._domain.topic(f"hetros/{plan.name}/hosts", HostState)
        self._writer = DataWriter(self._domain.participant, topic, qos=qos)
        self._reader = DataReader(self._domain.participant, topic, qos=qos)
        self._domain.watch(self._reader, self._news)

    def announce(self, phase: str, **details: Any) -> None:
        """Tell the other hosts this host's phase: ``ready``, ``running``, or ``leaving`` (with
        ``ok`` and ``why``) as it ends in order, so that its going is not taken for a loss."""
        state = json.dumps({"hash": self.plan.project_hash, "phase": phase, **details})
        self._writer.write(HostState(host=self.me, state=state))

    def _news(self) -> None:
        for sample in self._reader.take(64):
            info = sample.sample_info
            host = sample.key_sample.host if not info.valid_data else sample.host
            if host == self.me or host not in self.plan.hosts:
                continue
            event: dict[str, Any]
            with self._lock:
                if info.valid_data:
                    state = self._states[host] = json.loads(sample.state)
                    back = host in self._gone
                    self._gone.discard(host)
                    if state.get("phase") == "leaving":
                        event = {"event": "host_leaving", "host": host, "ok": bool(state.get("ok")),
                                 "why": str(state.get("why", ""))}
                    else:
                        event = {"event": "host_back" if back else "host_state", "host": host}
                elif info.instance_state & (InstanceState.NotAliveNoWriters | InstanceState.NotAliveDisposed):
                    left = self._states.pop(host, {}).get("phase") == "leaving"
                    self._gone.add(host)
                    if left:
                        continue  # it said goodbye first: its going is no loss
                    event = {"event": "host_lost", "host": host}
                else:
                    continue
            self._on_change(event)

    def mismatch(self) -> str:
        """Why another host is not running this project, or ''."""
        with self._lock:
            for host, state in sorted(self._states.items()):
                if state["hash"] != self.plan.project_hash:
                    return (f"host {host} ({self.plan.hosts[host].address}) runs project {self.plan.name} with hash "
                            f"{state['hash']}, this host ({self.me}) with {self.plan.project_hash}: run the same "
                            "checkout of the project and its messages on every host")
        return ""

    def missing(self) -> list[str]:
        """The hosts that have not announced that they are ready."""
        with self._lock:
            return [h for h in self.plan.hosts if h != self.me
                    and self._states.get(h, {}).get("phase") not in ("ready", "running")]

    def close(self) -> None:
        self._domain.close()
