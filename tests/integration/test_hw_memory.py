"""Hardware nodes reading and writing messages in memory: the images never pass through the CPU, the
hardware reaches only the arrays it was given, and the project file's ``memory:`` is checked."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hetros import CheckError, HardwareError
from hetros.hw.reference import sobel
from hetros.msg import registry
from hetros.project import load_project, plan

pytest.importorskip("amaranth")
pytestmark = [pytest.mark.rtl,
              pytest.mark.skipif(shutil.which("verilator") is None, reason="Debian's verilator is not installed")]

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "sobel_hw"


def test_the_memory_sobel_is_pixel_exact_with_no_cpu_copy(tmp_path: Path) -> None:
    """examples/sobel_hw/project_mem.yaml: 640x480 frames from the camera's slot to the display's, in place."""
    done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(EXAMPLE / "project_mem.yaml"), "--duration",
                           "120"], capture_output=True, text=True, timeout=240, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "4 frames, every pixel equal to the software filters" in done.stderr
    line = re.search(r"hardware node sobel in memory: 4 messages, (\d+) cycles per message, (\d+) beats read and "
                     r"(\d+) written over AXI4, (\d+) array bytes copied by the CPU per message", done.stderr)
    assert line is not None, done.stderr
    cycles, read, written, copied = map(int, line.groups())
    assert read == written == 4 * 640 * 480 // 8
    assert copied == 0
    assert 640 * 480 // 8 <= cycles < 2 * 640 * 480 // 8  # a beat of pixels a cycle, as the streaming Sobel


def test_the_memory_sobel_runs_on_a_board_target_through_pynqs_surface(tmp_path: Path) -> None:
    """project_mem.yaml with board: set: the gateway takes the board's path (PYNQ's allocate and DMAs, the
    simulated overlay here), the node reads and writes contiguous buffers by physical address, pixel-exact."""
    text = (EXAMPLE / "project_mem.yaml").read_text().replace("part: xczu7ev-ffvc1156-2-e}", "board: zcu104}")
    assert "board: zcu104" in text
    text = text.replace("height: 480, width: 640", "height: 48, width: 64").replace("width: 640}", "width: 64}")
    (tmp_path / "project.yaml").write_text(text)
    (tmp_path / "nodes.py").write_text((EXAMPLE / "nodes.py").read_text())
    done = subprocess.run([sys.executable, "-m", "hetros", "launch", str(tmp_path / "project.yaml"), "--duration",
                           "120"], capture_output=True, text=True, timeout=240, check=False, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "4 frames, every pixel equal to the software filters" in done.stderr
    assert re.search(r"fpga target fpga on board zcu104 through SimulatedOverlay \(\d+ DMA channels\)", done.stderr)


def _small_plan(tmp_path: Path) -> object:
    text = (EXAMPLE / "project_mem.yaml").read_text().replace("height: 480, width: 640", "height: 12, width: 16")
    (tmp_path / "project.yaml").write_text(text.replace("width: 640}", "width: 16}"))
    (tmp_path / "nodes.py").write_text((EXAMPLE / "nodes.py").read_text())
    return plan(load_project(tmp_path / "project.yaml"))


def _run_one(top: object, descriptor: list[int]) -> None:
    from hetros.hw.sim._verilator import VerilatedTop

    assert isinstance(top, VerilatedTop)
    top.push(0, np.array(descriptor, "<u8").tobytes())
    for _ in range(100):
        top.run(1_000_000, 1_000_000)
        if top.front(0) is not None:
            top.drop(0)
            return
    raise AssertionError("no completion")


def test_the_hardware_reaches_only_the_arrays_it_was_given(tmp_path: Path) -> None:
    from hetros.hw.sim._cosim import TargetSimulation

    simulation = TargetSimulation(_small_plan(tmp_path), "fpga", registry())  # type: ignore[arg-type]
    top = simulation.top
    try:
        image = np.random.default_rng(1).integers(0, 256, (12, 16), dtype=np.uint8)
        edges = np.zeros_like(image)
        source = top.allow(image.ctypes.data, image.nbytes, False)  # type: ignore[union-attr]
        target = top.allow(edges.ctypes.data, edges.nbytes, True)  # type: ignore[union-attr]
        # physical addresses, as on a board: page-aligned in the simulated DDR, not this process' pointers
        assert source % 4096 == target % 4096 == 0 and source != image.ctypes.data and 0x4000_0000 <= source
        _run_one(top, [source, image.nbytes, target, edges.nbytes])
        assert np.array_equal(edges, sobel(image))
        stray = np.zeros_like(image)  # never allowed: the hardware must not write here
        with pytest.raises(HardwareError, match=r"hardware node sobel's memory port \(mem\): wrote at 0x[0-9a-f]+, "
                                                r"outside the messages it was given"):
            _run_one(top, [source, image.nbytes, stray.ctypes.data, stray.nbytes])
        assert not stray.any()
        # the process' own pointer of an allowed array is no address the hardware can use
        top.forbid(target)  # type: ignore[union-attr]
        with pytest.raises(HardwareError, match=r"outside the messages it was given"):
            _run_one(top, [source, image.nbytes, edges.ctypes.data, edges.nbytes])
    finally:
        simulation.close()


@pytest.mark.parametrize(("change", "expected"), [
    ("target: fpga, memory: [/image_raw, /image_edges]", "memory: is for a hardware node"),
    ("memory: [/image_raw, /image_edges]", None),
    ("memory: [/image_raw]", "one topic the node subscribes .* and one it publishes .*, not 1 and 0"),
    ("memory: [/image_raw, /nowhere]", "/nowhere must be topics node sobel subscribes or publishes"),
])
def test_memory_topics_are_checked(tmp_path: Path, change: str, expected: str | None) -> None:
    text = (EXAMPLE / "project_mem.yaml").read_text().replace("memory: [/image_raw, /image_edges]", change)
    if change.startswith("target: fpga"):  # the node moved off its fpga target, memory: kept
        text = text.replace("target: fpga, target: fpga,", "target: io,")
    (tmp_path / "project.yaml").write_text(text)
    (tmp_path / "nodes.py").write_text((EXAMPLE / "nodes.py").read_text())
    if expected is None:
        plan(load_project(tmp_path / "project.yaml"))
        return
    with pytest.raises(CheckError, match=expected):
        plan(load_project(tmp_path / "project.yaml"))
