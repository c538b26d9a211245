"""The board surface: an fpga target reached as PYNQ reaches a Zynq board.

``open_overlay`` returns an object with PYNQ's shape: ``overlay.<dma>.sendchannel`` and
``.recvchannel`` with ``transfer(buffer)``, ``wait()``, ``idle`` and ``transferred``, and
``allocate(shape, dtype)`` for buffers the DMAs can reach. On a board with ``pynq`` installed
(``pip install hetros[board]``) and the exported bitstream beside the manifest, it is PYNQ's own
``Overlay``; elsewhere the target's simulator stands behind the same surface, so the code path a
board takes (``launch._gateway``'s board mode) is the one the tests run.

The DMA names, their channels and what topic each carries come from the manifest ``hetros hw
export`` writes (``<top>.board.json``).
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..._errors import HardwareError

__all__ = ["SimulatedOverlay", "allocate", "open_overlay", "read_manifest", "release"]


def read_manifest(path: Path) -> dict[str, Any]:
    try:
        manifest: dict[str, Any] = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise HardwareError(f"{path}: not a board manifest ({exc}); write one with `hetros hw export`") from None
    for key in ("board", "dmas", "bitstream"):
        if key not in manifest:
            raise HardwareError(f"{path}: a board manifest needs {key!r}; write it anew with `hetros hw export`")
    return manifest


class _Buffer(np.ndarray):
    """A buffer a DMA can reach: PYNQ's ``PynqBuffer`` shape (``physical_address``, ``flush``)."""

    physical_address: int

    def flush(self) -> None:
        """The cache written back to memory (nothing to do where the simulator reads it)."""

    def invalidate(self) -> None:
        """The cache dropped so the DMA's writes show (nothing to do where the simulator writes it)."""


def allocate(shape: int | tuple[int, ...], dtype: Any = np.uint8, overlay: Any = None) -> Any:
    """A buffer the hardware can reach, physically contiguous: PYNQ's ``allocate`` (CMA) on a board. Here, host
    memory that the simulated ``overlay``'s target places in its simulated physical address space (where its
    memory nodes reach it, by that address, as on a board); without an overlay, a DMA buffer that the
    simulated DMAs read and write directly."""
    if _on_board():
        import pynq  # type: ignore[import-not-found]

        return pynq.allocate(shape, dtype)
    buffer = np.zeros(shape, dtype).view(_Buffer)
    if isinstance(overlay, SimulatedOverlay):
        buffer.physical_address = overlay.top.allow(buffer.ctypes.data, buffer.nbytes, True)
        overlay.placed.append(buffer)
    else:
        buffer.physical_address = buffer.ctypes.data
    return buffer


def release(buffer: Any, overlay: Any = None) -> None:
    """Give a buffer from :func:`allocate` back (PYNQ's ``freebuffer``; here, out of the simulated memory)."""
    if _on_board():
        buffer.freebuffer()
    elif isinstance(overlay, SimulatedOverlay) and any(b is buffer for b in overlay.placed):
        overlay.top.forbid(buffer.physical_address)
        overlay.placed = [b for b in overlay.placed if b is not buffer]


def _on_board() -> bool:
    """PYNQ installed on a Zynq whose FPGA Linux can program."""
    return importlib.util.find_spec("pynq") is not None and Path("/sys/class/fpga_manager/fpga0").exists()


class _SendChannel:
    """Memory to the hardware (MM2S): a transfer queues the buffer's bytes at the port as one message."""

    def __init__(self, overlay: SimulatedOverlay, port: int) -> None:
        self._overlay, self._port = overlay, port
        self.transferred = 0

    def transfer(self, buffer: Any, start: int = 0, nbytes: int = 0) -> None:
        data = memoryview(buffer).cast("B")[start:start + nbytes if nbytes else None]
        self._overlay.top.loan_input(self._port, len(data))[:] = data
        self.transferred = len(data)

    @property
    def idle(self) -> bool:
        if self._overlay.top.queued(self._port):
            self._overlay.step()
        return bool(self._overlay.top.queued(self._port) == 0)

    def wait(self) -> None:
        while not self.idle:
            pass


class _RecvChannel:
    """The hardware to memory (S2MM): a transfer arms the buffer; the next message out of the port lands in it."""

    def __init__(self, overlay: SimulatedOverlay, port: int) -> None:
        self._overlay, self._port = overlay, port
        self._buffer: memoryview | None = None
        self.transferred = 0

    def transfer(self, buffer: Any, start: int = 0, nbytes: int = 0) -> None:
        self._buffer = memoryview(buffer).cast("B")[start:start + nbytes if nbytes else None]
        self.transferred = 0

    def _land(self) -> bool:
        if self._buffer is None:
            return True
        body = self._overlay.top.front(self._port)
        if body is None:
            return False
        if len(body) > len(self._buffer):
            raise HardwareError(f"a message of {len(body)} bytes came out for a buffer of {len(self._buffer)}: "
                                "allocate a larger receive buffer")
        self._buffer[:len(body)] = body
        self.transferred = len(body)
        del body
        self._overlay.top.drop(self._port)
        self._buffer = None
        return True

    @property
    def idle(self) -> bool:
        if self._land():
            return True
        self._overlay.step()
        return self._land()

    def wait(self) -> None:
        while not self.idle:
            pass


class _Dma:
    def __init__(self, overlay: SimulatedOverlay, entry: dict[str, Any], port: int) -> None:
        self.description = entry
        channel = _SendChannel(overlay, port) if entry["channel"] == "sendchannel" else _RecvChannel(overlay, port)
        self.sendchannel = channel if isinstance(channel, _SendChannel) else None
        self.recvchannel = channel if isinstance(channel, _RecvChannel) else None


class SimulatedOverlay:
    """PYNQ's ``Overlay`` with the target's simulator behind its DMAs: ``overlay.axi_dma_0.sendchannel``..."""

    # cycles one poll of a channel may run before it answers
    STEP_CYCLES = 200_000

    def __init__(self, manifest: dict[str, Any], simulation: Any) -> None:
        self.manifest = manifest
        self.simulation = simulation
        self.top = simulation.top
        self.cycles_run = 0
        self.placed: list[Any] = []  # buffers allocated in the simulated physical memory
        by_prefix = {p.port.prefix: p for p in (*simulation.inputs, *simulation.outputs)}
        self.ip_dict: dict[str, dict[str, Any]] = {}
        for entry in manifest["dmas"]:
            port = by_prefix.get(entry["interface"])
            if port is None:
                raise HardwareError(f"the board manifest's {entry['name']} feeds {entry['interface']}, which the "
                                    "target's hardware does not have: export the board files anew")
            setattr(self, entry["name"], _Dma(self, entry, port.index))
            self.ip_dict[entry["name"]] = {"phys_addr": int(entry["base_address"], 16), "type": "axi_dma"}

    def step(self) -> None:
        """Let the hardware run (a board's runs by itself): until something came out, or a while."""
        before = self.top.cycle
        self.top.run(self.STEP_CYCLES, 256)
        self.cycles_run += self.top.cycle - before

    def free(self) -> None:
        self.simulation.close()


def open_overlay(manifest_path: Path, simulation: Any = None) -> Any:
    """PYNQ's ``Overlay`` of the exported bitstream on a board, else ``SimulatedOverlay`` over ``simulation``."""
    manifest = read_manifest(manifest_path)
    bitstream = manifest_path.parent / manifest["bitstream"]
    if _on_board() and bitstream.exists():
        import pynq

        return pynq.Overlay(str(bitstream))
    if simulation is None:
        raise HardwareError(f"no board here (pynq with an fpga manager) for {bitstream}, and no simulator to stand "
                            "in for it")
    return SimulatedOverlay(manifest, simulation)
