"""``sim: amaranth``: a target's top module in Amaranth's own simulator, behind the same surface as Verilator's.

Pure Python, so no compiler is needed, and about a thousand times slower than Verilator
(thousands of cycles a second): for small designs and small messages. It keeps the gateway's
contract of ``_verilator.VerilatedTop`` message for message: queues per port, the AXI4-Stream
rules watched on every output and every hardware node's stream, a run that returns when
Python has something to do.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from amaranth import ClockDomain, Module

from ..._errors import HardwareError
from ._verilator import BEAT, IDLE, INPUT_DRY, OUTPUT_ENDED, VIOLATION, StreamPort, TraceSetting

_PERIOD = 1e-8
# quiet cycles with an output held back by software after which a run returns (as the Verilator harness's)
HELD_QUIET = 256


@dataclass
class _Port:
    """What a port counts (``stats``): messages, beats, and cycles from a message's first beat to its last."""

    messages: int = 0
    beats: int = 0
    busy: int = 0
    started: int = 0
    waited: int = 0  # of the busy cycles, those a full software subscriber held an output back


@dataclass
class _In(_Port):
    queue: deque[bytearray] = field(default_factory=deque)
    offset: int = 0


@dataclass
class _Out(_Port):
    current: bytearray = field(default_factory=bytearray)
    done: deque[bytes] = field(default_factory=deque)
    limit: int = 4
    held: tuple[int, int, int] | None = None


class AmaranthTop:
    """One instance of a top module in Amaranth's simulator (see the module's docstring)."""

    def __init__(self, top: Any, ports: list[StreamPort], data_width: int, monitored: list[tuple[str, str]]) -> None:
        from amaranth.sim import Simulator

        wrapper = Module()
        wrapper.domains.sync = ClockDomain("sync")
        wrapper.submodules.top = top
        self._top = top
        self.inputs = [p for p in ports if p.feeds_design]
        self.outputs = [p for p in ports if not p.feeds_design]
        self._per_beat = data_width // 8
        self._monitored = monitored
        self._in = [_In() for _ in self.inputs]
        self._out = [_Out() for _ in self.outputs]
        self._cycle = 0
        self._events = 0
        self._error = ""
        self._simulator = Simulator(wrapper)
        self._simulator.add_clock(_PERIOD)
        self._simulator.add_testbench(self._bench)
        self._closed = False
        self._waited = 0  # cycles any output was held back by software
        self._held = False  # the last cycle, an output was
        self._trace: Any = None  # Amaranth's waveform writer, entered by ``trace``
        self._trace_path = Path()
        self._trace_note = ""

    async def _bench(self, ctx: Any) -> None:
        per_beat = self._per_beat
        while True:
            for port, state in zip(self.inputs, self._in, strict=True):
                signals = self._top.ports[port.prefix]
                if state.queue:
                    message = state.queue[0]
                    chunk = bytes(message[state.offset:state.offset + per_beat])
                    ctx.set(signals["tdata"], int.from_bytes(chunk, "little"))
                    ctx.set(signals["tkeep"], (1 << len(chunk)) - 1)
                    ctx.set(signals["tlast"], int(state.offset + per_beat >= len(message)))
                    ctx.set(signals["tvalid"], 1)
                else:
                    ctx.set(signals["tvalid"], 0)
            held = False
            for port, sink in zip(self.outputs, self._out, strict=True):
                full = len(sink.done) >= sink.limit
                held |= full
                sink.waited += full and bool(sink.current)
                ctx.set(self._top.ports[port.prefix]["tready"], int(not full))
            self._waited += held
            self._held = held
            fired = [bool(ctx.get(self._top.ports[p.prefix]["tvalid"]) and ctx.get(self._top.ports[p.prefix]["tready"]))
                     for p in self.inputs]
            what = 0
            for port, sink in zip(self.outputs, self._out, strict=True):
                what |= self._watch(ctx, port, sink)
            if self._monitored:
                broken = ctx.get(self._top.violations)
                for index, (label, rule) in enumerate(self._monitored):
                    if broken >> index & 1:
                        what |= self._fail(label, rule)
                        break
            await ctx.tick()
            for state, took in zip(self._in, fired, strict=True):
                if took:
                    what |= self._taken(state)
                elif held and state.offset > 0:
                    state.waited += 1
            self._cycle += 1
            self._events |= what

    def _fail(self, label: str, what: str) -> int:
        self._error = f"{label}: {what} at cycle {self._cycle}"
        return VIOLATION

    def _taken(self, state: _In) -> int:
        message = state.queue[0]
        if state.offset == 0:
            state.started = self._cycle
        state.offset += self._per_beat
        state.beats += 1
        if state.offset < len(message):
            return BEAT
        state.busy += self._cycle - state.started + 1
        state.messages += 1
        state.queue.popleft()
        state.offset = 0
        return BEAT | (INPUT_DRY if not state.queue else 0)

    def _watch(self, ctx: Any, port: StreamPort, state: _Out) -> int:
        signals = self._top.ports[port.prefix]
        valid, ready = ctx.get(signals["tvalid"]), ctx.get(signals["tready"])
        shown = (ctx.get(signals["tdata"]), ctx.get(signals["tkeep"]), ctx.get(signals["tlast"]))
        what = 0
        if state.held is not None and not valid:
            what |= self._fail(port.label, "TVALID dropped before TREADY")
        elif state.held is not None and shown != state.held:
            what |= self._fail(port.label, "TDATA/TKEEP/TLAST changed before TREADY")
        state.held = shown if valid and not ready else None
        if not (valid and ready):
            return what
        data, keep, last = shown
        count = 0
        while count < self._per_beat and keep >> count & 1:
            count += 1
        if keep >> count:
            what |= self._fail(port.label, "TKEEP not contiguous low bytes")
        if not last and count != self._per_beat:
            what |= self._fail(port.label, "a partial beat without TLAST")
        if not state.current:
            state.started = self._cycle
        state.current += data.to_bytes(self._per_beat, "little")[:count]
        state.beats += 1
        what |= BEAT
        if last:
            state.busy += self._cycle - state.started + 1
            state.messages += 1
            state.done.append(bytes(state.current))
            state.current = bytearray()
            what |= OUTPUT_ENDED
        return what

    # -- the surface the gateway uses (VerilatedTop's) --------------------------------------------

    def push(self, port: int, body: bytes) -> None:
        if not body:
            raise HardwareError(f"{self.inputs[port].label}: a message needs at least one byte")
        self._in[port].queue.append(bytearray(body))

    def loan_input(self, port: int, size: int) -> memoryview:
        if size < 1:
            raise HardwareError(f"{self.inputs[port].label}: a message needs at least one byte")
        buffer = bytearray(size)
        self._in[port].queue.append(buffer)
        return memoryview(buffer)

    def queued(self, port: int) -> int:
        return len(self._in[port].queue)

    def set_output_limit(self, port: int, messages: int) -> None:
        self._out[port].limit = messages

    def pop(self, port: int) -> bytes | None:
        done = self._out[port].done
        return done.popleft() if done else None

    def front(self, port: int) -> memoryview | None:
        done = self._out[port].done
        return memoryview(done[0]) if done else None

    def drop(self, port: int) -> None:
        if self._out[port].done:
            self._out[port].done.popleft()

    def partial(self, port: int) -> int:
        return len(self._out[port].current)

    @property
    def cycle(self) -> int:
        return self._cycle

    def stats(self, output: bool, port: int) -> tuple[int, int, int]:
        state: _Port = self._out[port] if output else self._in[port]
        return state.messages, state.beats, state.busy - state.waited

    def waited(self, output: bool | None = None, port: int = 0) -> int:
        if output is None:
            return self._waited
        return (self._out[port] if output else self._in[port]).waited

    def run(self, max_cycles: int, idle: int) -> int:
        """Run cycle by cycle until something needs Python, ``idle`` quiet cycles, or ``max_cycles``."""
        seen, quiet, still = 0, 0, 0
        for _ in range(max_cycles):
            self._events = 0
            self._simulator.run_until((self._cycle + 1) * _PERIOD)
            what = self._events
            seen |= what
            if what & VIOLATION:
                note = self.finish_trace()
                raise HardwareError(f"{self._error}; {note}" if note else self._error)
            if what & (OUTPUT_ENDED | INPUT_DRY):
                return seen
            if what & BEAT:
                quiet = still = 0
                continue
            still += 1
            if self._held and still >= HELD_QUIET:
                return seen | IDLE
            quiet += 1
            if not any(state.queue for state in self._in) and quiet >= idle:
                return seen | IDLE
        return seen

    def trace(self, base: Path, setting: TraceSetting, clock_mhz: float) -> None:
        """Write the waveform of the whole run to ``base.vcd`` (Amaranth's writer keeps no window: the designs
        its simulator suits are small, and its runs short)."""
        del setting, clock_mhz
        base.parent.mkdir(parents=True, exist_ok=True)
        self._trace_path = base.with_name(base.name + ".vcd")
        self._trace = self._simulator.write_vcd(str(self._trace_path))
        self._trace.__enter__()

    def finish_trace(self) -> str:
        """Close the waveform: where it is and which cycles it holds ("" when nothing was traced)."""
        if self._trace is not None:
            self._trace.__exit__(None, None, None)
            self._trace = None
            self._trace_note = f"waveform: {self._trace_path} (cycles 0 to {self._cycle - 1})"
        return self._trace_note

    def close(self) -> None:
        self.finish_trace()
        self._closed = True
