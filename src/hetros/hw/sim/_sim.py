"""A topic network in Amaranth's simulator: publishers, subscribers and a scoreboard.

One testbench drives every endpoint cycle by cycle, as AXI4-Stream masters and slaves do:
a publisher may idle between beats but never takes TVALID back once shown; a subscriber
may hold TREADY low (back-pressure) at random. What each subscriber receives is cut at
TLAST into messages and checked against what each publisher sent: every message whole, in
each publisher's order, none interleaved.
"""

from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..._errors import HardwareError
from ..streams._axi import TopicNetwork
from ..streams._beats import Beats, from_beats, to_beats


@dataclass
class _Source:
    messages: list[Beats]
    message: int = 0
    beat: int = 0
    showing: bool = False
    first_shown: int = -1

    def pending(self) -> bool:
        return self.message < len(self.messages)


@dataclass
class SimResult:
    """What a simulation saw: cycles run, messages per subscriber, the cycle each one ended on.

    ``idle`` and ``stall`` are the per-cycle decisions it drew (a bit per publisher: do not
    start a beat this cycle; a bit per subscriber: hold TREADY low), so another simulator can
    replay exactly the same run.
    """

    cycles: int
    received: list[list[bytes]]
    done_at: list[list[int]] = field(default_factory=list)
    idle: list[int] = field(default_factory=list)
    stall: list[int] = field(default_factory=list)


def simulate(network: TopicNetwork, messages: list[list[bytes]], *, idle: float = 0.0, stall: float = 0.0,
             seed: int = 0, max_cycles: int = 10_000_000) -> SimResult:
    """Send ``messages[i]`` from publisher ``i``; return what every subscriber received, in order."""
    from amaranth import ClockDomain, Module
    from amaranth.sim import Simulator

    if len(messages) != network.publishers:
        raise HardwareError(f"messages must list one sequence per publisher ({network.publishers}), "
                            f"not {len(messages)}")
    rng = random.Random(seed)
    sources = [_Source([to_beats(m, network.data_width) for m in sent]) for sent in messages]
    pubs = [getattr(network, f"pub{i}") for i in range(network.publishers)]
    subs = [getattr(network, f"sub{j}") for j in range(network.subscribers)]
    expected = sum(len(sent) for sent in messages)
    received: list[list[bytes]] = [[] for _ in subs]
    done_at: list[list[int]] = [[] for _ in subs]
    partial: list[list[tuple[int, int]]] = [[] for _ in subs]
    per_beat = network.data_width // 8
    held: list[tuple[int, int, int, int] | None] = [None for _ in subs]  # a beat shown and not yet taken
    # who drives each stream the testbench takes from, as errors name it
    labels: list[str] = list(getattr(network, "output_labels", [f"subscriber {j}" for j in range(len(subs))]))
    result = SimResult(0, received, done_at)

    async def bench(ctx: Any) -> None:
        cycle = 0
        while any(len(r) < expected for r in received):
            if cycle >= max_cycles:
                raise HardwareError(f"the topic network moved {sum(map(len, received))} of "
                                    f"{expected * len(subs)} messages in {max_cycles:,} cycles: it is stuck")
            idle_bits = sum((rng.random() < idle) << i for i in range(len(pubs)))
            stall_bits = sum((rng.random() < stall) << j for j in range(len(subs)))
            result.idle.append(idle_bits)
            result.stall.append(stall_bits)
            for index, (source, port) in enumerate(zip(sources, pubs, strict=True)):
                if not source.showing and source.pending() and not idle_bits >> index & 1:
                    source.showing = True
                if source.showing:
                    beats = source.messages[source.message]
                    ctx.set(port.tdata, int.from_bytes(beats.data[source.beat].tobytes(), "little"))
                    ctx.set(port.tkeep, int(beats.keep[source.beat]))
                    ctx.set(port.tlast, int(source.beat == len(beats) - 1))
                ctx.set(port.tvalid, int(source.showing))
            ready = [not stall_bits >> j & 1 for j in range(len(subs))]
            for port, wants in zip(subs, ready, strict=True):
                ctx.set(port.tready, int(wants))
            for source, port in zip(sources, pubs, strict=True):
                if source.showing and ctx.get(port.tready):
                    source.showing = False
                    source.beat += 1
                    if source.beat == len(source.messages[source.message]):
                        source.message += 1
                        source.beat = 0
            for index, port in enumerate(subs):
                shown = (ctx.get(port.tvalid), ctx.get(port.tdata), ctx.get(port.tkeep), ctx.get(port.tlast))
                if held[index] is not None and shown != held[index]:
                    what = ("TVALID dropped" if not shown[0] else "TDATA/TKEEP/TLAST changed")
                    raise HardwareError(f"{labels[index]}'s stream: {what} at cycle {cycle} before the beat was "
                                        "taken (AXI4-Stream holds a shown beat until TREADY)")
                held[index] = shown if shown[0] and not ready[index] else None
            for index, (port, wants) in enumerate(zip(subs, ready, strict=True)):
                if wants and ctx.get(port.tvalid):
                    partial[index].append((ctx.get(port.tdata), ctx.get(port.tkeep)))
                    if ctx.get(port.tlast):
                        words, keeps = zip(*partial[index], strict=True)
                        data = np.frombuffer(b"".join(w.to_bytes(per_beat, "little") for w in words), np.uint8)
                        beats = Beats(data.reshape(len(words), per_beat).copy(), np.array(keeps, np.uint64))
                        received[index].append(from_beats(beats))
                        done_at[index].append(cycle)
                        partial[index].clear()
            await ctx.tick()
            cycle += 1
        result.cycles = cycle

    harness = Module()
    harness.submodules.network = network
    harness.domains.sync = ClockDomain()  # a network of wiring only has no clock of its own
    sim = Simulator(harness)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return result


def check_delivery(sent: list[list[bytes]], result: SimResult) -> None:
    """Every subscriber got every message whole and in each publisher's order (messages start with
    their publisher's index, as the scoreboard tests make them)."""
    for index, got in enumerate(result.received):
        queues = [list(messages) for messages in sent]
        for message in got:
            publisher = message[0]
            if publisher >= len(queues) or not queues[publisher] or queues[publisher][0] != message:
                raise HardwareError(f"subscriber {index} got a message out of order, cut or interleaved: "
                                    f"{message[:16].hex()}...")
            queues[publisher].pop(0)
        missing = sum(len(q) for q in queues)
        if missing:
            raise HardwareError(f"subscriber {index} is missing {missing} message(s)")
