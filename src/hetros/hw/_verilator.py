"""An fpga target's top module compiled by Verilator, driven message by message from Python.

Python cannot touch a port every cycle and reach a million cycles a second, so the cycle
loop is C++: a harness generated for the top's AXI4-Stream ports holds, per input port, a
queue of whole messages (each a CDR body, cut into beats as ``_beats`` says) and, per output
port, the messages cut at TLAST. Python pushes messages, asks for a run of cycles and pops
what came out; a run returns as soon as there is something for Python to do (an output
message ended, an input queue ran dry, the design went idle, an AXI4-Stream rule broke).

The compiled simulator is cached by the hash of the Verilog and the harness, so a launch
compiles once per design and machine (``$XDG_CACHE_HOME/hetros/verilator``).
"""

from __future__ import annotations

import ctypes
import hashlib
import json
import os
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path

from .._errors import HardwareError

# bumped when the harness text changes in a way its hash would not show (compiler flags)
_HARNESS_VERSION = "5"


@dataclass(frozen=True)
class MemoryPort:
    """A hardware node's AXI4 master port at the top (``m_axi_<node>``): the harness serves it from this
    process' memory, within the windows Python allows (:meth:`VerilatedTop.allow`)."""

    prefix: str
    label: str


@dataclass(frozen=True)
class StreamPort:
    """One AXI4-Stream port of the top: ``prefix`` is ``s_axis_...`` (the simulator feeds the design)
    or ``m_axis_...`` (the design feeds the simulator); ``label`` names it in errors."""

    prefix: str
    feeds_design: bool
    label: str


def cache_root() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "hetros" / "verilator"


def verilator_command() -> str:
    found = shutil.which("verilator")
    if found is None:
        raise HardwareError("sim: verilator needs Debian's verilator package (apt-get install verilator; "
                            "`make install-test` installs it when run as root), or choose sim: amaranth for a "
                            "small design")
    return found


# The cycle loop's fixed part: ports are indices here; the generated part reads and drives the signals.
_HARNESS = r"""
static const size_t MAX_MESSAGE = size_t(1) << 30;
static const int KEEP_BYTES = (PER_BEAT + 7) / 8;

template <class T> static inline void put(T& dst, const uint8_t* src, int n) {
  uint64_t v = 0; std::memcpy(&v, src, n); dst = (T)v; }
template <std::size_t W> static inline void put(VlWide<W>& dst, const uint8_t* src, int n) {
  std::memset(dst.data(), 0, W * 4); std::memcpy(dst.data(), src, n); }
template <class T> static inline void get(const T& src, uint8_t* dst, int n) {
  uint64_t v = (uint64_t)src; std::memcpy(dst, &v, n); }
template <std::size_t W> static inline void get(const VlWide<W>& src, uint8_t* dst, int n) {
  std::memcpy(dst, src.data(), n); }

struct InPort {
  std::deque<std::vector<uint8_t>> queue; size_t offset = 0;
  uint64_t messages = 0, beats = 0, busy = 0, started = 0;
};
struct OutPort {
  std::vector<uint8_t> current; std::deque<std::vector<uint8_t>> done; size_t limit = 4;
  uint64_t messages = 0, beats = 0, busy = 0, started = 0;
  bool held = false; uint8_t held_data[PER_BEAT]; uint8_t held_keep[KEEP_BYTES]; int held_last = 0;
};
// an AXI4 slave whose memory is this process' own: the windows Python allowed (the messages' arrays)
struct Window { uint64_t start, end; bool writable; };
struct MemPort {
  bool ar_busy = false; uint64_t ar_addr = 0; int ar_left = 0; int ar_wait = 0;
  bool aw_busy = false; uint64_t aw_addr = 0; int aw_left = 0; bool b_pending = false;
  std::string bad; uint64_t reads = 0, writes = 0;
};
static const int READ_LATENCY = 8;
struct Sim {
  VerilatedContext* context; TOP* top;
  InPort in[N_IN > 0 ? N_IN : 1]; OutPort out[N_OUT > 0 ? N_OUT : 1];
  MemPort mem[N_MEM > 0 ? N_MEM : 1]; std::vector<Window> windows;
  uint64_t cycle = 0; std::string error;
};

// bytes from ``address`` (up to ``n``) inside one allowed window, 0 when none holds it
static size_t reachable(Sim* s, uint64_t address, size_t n, bool write) {
  for (const Window& w : s->windows)
    if (address >= w.start && address < w.end && (!write || w.writable))
      return (size_t)(w.end - address) < n ? (size_t)(w.end - address) : n;
  return 0;
}
static std::string hex(uint64_t v) {
  char b[32]; std::snprintf(b, sizeof b, "0x%llx", (unsigned long long)v); return b; }

static int fail(Sim* s, const char* label, const char* what) {
  s->error = std::string(label) + ": " + what + " at cycle " + std::to_string(s->cycle); return 8; }

// the beat an input port shows this cycle: the next bytes of its first queued message
static bool show(Sim* s, int i, uint8_t* data, uint8_t* keep, int* last) {
  InPort& p = s->in[i];
  std::memset(data, 0, PER_BEAT); std::memset(keep, 0, KEEP_BYTES); *last = 0;
  if (p.queue.empty()) return false;
  const std::vector<uint8_t>& m = p.queue.front();
  size_t left = m.size() - p.offset; int n = left < (size_t)PER_BEAT ? (int)left : PER_BEAT;
  std::memcpy(data, m.data() + p.offset, n);
  for (int b = 0; b < n; ++b) keep[b / 8] |= (uint8_t)(1u << (b % 8));
  *last = left <= (size_t)PER_BEAT; return true;
}

// after the clock edge: an input beat was taken
static int taken(Sim* s, int i) {
  InPort& p = s->in[i]; const std::vector<uint8_t>& m = p.queue.front();
  if (p.offset == 0) p.started = s->cycle;
  p.offset += PER_BEAT; ++p.beats;
  if (p.offset < m.size()) return 1;
  p.busy += s->cycle - p.started + 1; ++p.messages; p.queue.pop_front(); p.offset = 0;
  return p.queue.empty() ? 5 : 1;
}

// an output port's signals this cycle, checked against the AXI4-Stream rules and collected at TLAST
static int watch(Sim* s, int j, bool valid, bool ready, const uint8_t* data, const uint8_t* keep, int last) {
  OutPort& p = s->out[j]; const char* label = OUT_LABELS[j]; int what = 0;
  if (p.held && !valid) what |= fail(s, label, "TVALID dropped before TREADY");
  else if (p.held && (std::memcmp(data, p.held_data, PER_BEAT) || std::memcmp(keep, p.held_keep, KEEP_BYTES)
                      || last != p.held_last)) what |= fail(s, label, "TDATA/TKEEP/TLAST changed before TREADY");
  p.held = valid && !ready;
  if (p.held) {
    std::memcpy(p.held_data, data, PER_BEAT); std::memcpy(p.held_keep, keep, KEEP_BYTES); p.held_last = last; }
  if (!(valid && ready)) return what;
  int n = 0; while (n < PER_BEAT && (keep[n / 8] >> (n % 8) & 1)) ++n;
  for (int b = n; b < PER_BEAT; ++b)
    if (keep[b / 8] >> (b % 8) & 1) { what |= fail(s, label, "TKEEP not contiguous low bytes"); break; }
  if (!last && n != PER_BEAT) what |= fail(s, label, "a partial beat without TLAST");
  if (p.current.empty()) p.started = s->cycle;
  p.current.insert(p.current.end(), data, data + n); ++p.beats; what |= 1;
  if (p.current.size() > MAX_MESSAGE) what |= fail(s, label, "more than 1 GiB without TLAST");
  if (last) {
    p.busy += s->cycle - p.started + 1; ++p.messages;
    p.done.push_back(std::move(p.current)); p.current.clear(); what |= 2;
  }
  return what;
}

static void drive(Sim* s);
static int sample(Sim* s, bool* fired);
static void edge(Sim* s);

// one cycle; the bits: 1 a beat moved, 2 an output message ended, 4 an input queue ran dry, 8 a violation
static int cycle(Sim* s) {
  bool fired[N_IN > 0 ? N_IN : 1];
  drive(s); s->top->eval();
  int what = sample(s, fired);
  edge(s);
  for (int i = 0; i < N_IN; ++i) if (fired[i]) what |= taken(s, i);
  ++s->cycle; return what;
}

extern "C" {
void* hs_new() {
  Sim* s = new Sim; s->context = new VerilatedContext; s->top = new TOP{s->context};
  RESET;
  return s;
}
void hs_allow(void* h, uint64_t start, size_t size, int writable) {
  ((Sim*)h)->windows.push_back(Window{start, start + size, writable != 0}); }
void hs_forbid(void* h, uint64_t start) {
  std::vector<Window>& w = ((Sim*)h)->windows;
  for (size_t i = w.size(); i-- > 0;) if (w[i].start == start) w.erase(w.begin() + i); }
void hs_mem_stats(void* h, int port, uint64_t* into) {
  Sim* s = (Sim*)h; into[0] = s->mem[port].reads; into[1] = s->mem[port].writes; }
void hs_free(void* h) { Sim* s = (Sim*)h; s->top->final(); delete s->top; delete s->context; delete s; }
void hs_push(void* h, int port, const uint8_t* data, size_t size) {
  ((Sim*)h)->in[port].queue.emplace_back(data, data + size); }
uint8_t* hs_alloc(void* h, int port, size_t size) {
  std::deque<std::vector<uint8_t>>& q = ((Sim*)h)->in[port].queue; q.emplace_back(size); return q.back().data(); }
size_t hs_queued(void* h, int port) { return ((Sim*)h)->in[port].queue.size(); }
const uint8_t* hs_front(void* h, int port) {
  Sim* s = (Sim*)h; return s->out[port].done.empty() ? nullptr : s->out[port].done.front().data(); }
void hs_drop(void* h, int port) { Sim* s = (Sim*)h; if (!s->out[port].done.empty()) s->out[port].done.pop_front(); }
void hs_set_limit(void* h, int port, size_t limit) { ((Sim*)h)->out[port].limit = limit; }
long long hs_next_size(void* h, int port) {
  Sim* s = (Sim*)h; return s->out[port].done.empty() ? -1 : (long long)s->out[port].done.front().size(); }
int hs_pop(void* h, int port, uint8_t* buf) {
  Sim* s = (Sim*)h; if (s->out[port].done.empty()) return 0;
  std::vector<uint8_t>& m = s->out[port].done.front(); std::memcpy(buf, m.data(), m.size());
  s->out[port].done.pop_front(); return 1; }
size_t hs_partial(void* h, int port) { return ((Sim*)h)->out[port].current.size(); }
uint64_t hs_cycle(void* h) { return ((Sim*)h)->cycle; }
const char* hs_error(void* h) { return ((Sim*)h)->error.c_str(); }
void hs_stats(void* h, int output, int port, uint64_t* into) {
  Sim* s = (Sim*)h;
  if (output) { OutPort& p = s->out[port]; into[0] = p.messages; into[1] = p.beats; into[2] = p.busy; }
  else { InPort& p = s->in[port]; into[0] = p.messages; into[1] = p.beats; into[2] = p.busy; }
}
// up to max_cycles; ends early on an event Python must handle, or after idle quiet cycles with no input waiting
int hs_run(void* h, uint64_t max_cycles, uint64_t idle) {
  Sim* s = (Sim*)h; int seen = 0; uint64_t quiet = 0;
  for (uint64_t n = 0; n < max_cycles; ++n) {
    int what = cycle(s); seen |= what;
    if (what & 14) return seen;
    if (what & 1) { quiet = 0; continue; }
    bool waiting = false;
    for (int i = 0; i < N_IN; ++i) waiting |= !s->in[i].queue.empty();
    if (!waiting && ++quiet >= idle) return seen | 16;
  }
  return seen;
}
}
"""


def _c_strings(labels: list[str]) -> str:
    return "{" + ", ".join(json.dumps(label) for label in labels or [""]) + "}"


def harness_source(top: str, ports: list[StreamPort], data_width: int, clocked: bool,
                   monitored: list[tuple[str, str]] | None = None, memories: list[MemoryPort] | None = None) -> str:
    """The C++ of the cycle loop for ``top``'s ports (see the module's docstring)."""
    inputs = [p for p in ports if p.feeds_design]
    outputs = [p for p in ports if not p.feeds_design]
    reset = ("s->top->clk = 0; s->top->rst = 1; drive(s); s->top->eval(); for (int i = 0; i < 4; ++i) edge(s); "
             "s->top->rst = 0; s->top->eval()") if clocked else "drive(s); s->top->eval()"
    lines = [
        "// Generated by hetros.hw._verilator: DO NOT EDIT.",
        f'#include "V{top}.h"',
        "#include <verilated.h>",
        "#include <cstdint>", "#include <cstdio>", "#include <cstring>", "#include <deque>", "#include <string>",
        "#include <vector>",
        f"typedef V{top} TOP;",
        f"static const int PER_BEAT = {data_width // 8};",
        f"static const int SIZE_LOG2 = {(data_width // 8).bit_length() - 1};",
        f"static const int N_IN = {len(inputs)};",
        f"static const int N_OUT = {len(outputs)};",
        f"static const int N_MEM = {len(memories or [])};",
        f"static const char* MEM_LABELS[] = {_c_strings([m.label for m in memories or []])};",
        f"static const char* OUT_LABELS[] = {_c_strings([p.label for p in outputs])};",
        f"#define RESET {reset}",
        _HARNESS,
        "static void drive(Sim* s) {",
        "  uint8_t data[PER_BEAT]; uint8_t keep[KEEP_BYTES]; int last;",
    ]
    for i, port in enumerate(inputs):
        lines += [f"  {{ bool valid = show(s, {i}, data, keep, &last); TOP* t = s->top;",
                  f"    put(t->{port.prefix}_tdata, data, PER_BEAT); put(t->{port.prefix}_tkeep, keep, KEEP_BYTES);",
                  f"    t->{port.prefix}_tlast = last; t->{port.prefix}_tvalid = valid; }}"]
    for j, port in enumerate(outputs):
        lines += [f"  s->top->{port.prefix}_tready = s->out[{j}].done.size() < s->out[{j}].limit;"]
    for j, memory in enumerate(memories or []):
        p = memory.prefix
        lines += [f"  {{ MemPort& q = s->mem[{j}]; TOP* t = s->top; bool rv = q.ar_busy && q.ar_wait == 0;",
                  f"    t->{p}_arready = !q.ar_busy; t->{p}_rvalid = rv; t->{p}_rlast = rv && q.ar_left == 1;",
                  f"    t->{p}_rresp = 0; std::memset(data, 0, PER_BEAT);",
                  "    if (rv) { size_t n = reachable(s, q.ar_addr, PER_BEAT, false);",
                  "      if (!n) q.bad = \"read at \" + hex(q.ar_addr) + \", outside the messages it was given\";",
                  "      else std::memcpy(data, (const void*)q.ar_addr, n); }",
                  f"    put(t->{p}_rdata, data, PER_BEAT);",
                  f"    t->{p}_awready = !q.aw_busy; t->{p}_wready = q.aw_busy && !q.b_pending && q.aw_left > 0;",
                  f"    t->{p}_bvalid = q.b_pending; t->{p}_bresp = 0; }}"]
    lines += ["}", "", "static int sample(Sim* s, bool* fired) {",
              "  int what = 0; uint8_t data[PER_BEAT]; uint8_t keep[KEEP_BYTES]; TOP* t = s->top;"]
    for j, memory in enumerate(memories or []):
        p = memory.prefix
        lines += [f"  {{ MemPort& q = s->mem[{j}]; const char* label = MEM_LABELS[{j}];",
                  "    if (!q.bad.empty()) { what |= fail(s, label, q.bad.c_str()); q.bad.clear(); }",
                  f"    if (q.b_pending && t->{p}_bready) {{ q.b_pending = false; q.aw_busy = false; }}",
                  f"    if (t->{p}_awvalid && !q.aw_busy) {{ q.aw_busy = true; q.aw_addr = t->{p}_awaddr; "
                  f"q.aw_left = t->{p}_awlen + 1;",
                  f"      if (t->{p}_awburst != 1 || t->{p}_awsize != SIZE_LOG2) what |= fail(s, label, "
                  "\"a write burst must be INCR of data-width beats\"); }",
                  f"    else if (q.aw_busy && !q.b_pending && q.aw_left > 0 && t->{p}_wvalid) {{",
                  f"      get(t->{p}_wdata, data, PER_BEAT); get(t->{p}_wstrb, keep, KEEP_BYTES);",
                  "      size_t n = reachable(s, q.aw_addr, PER_BEAT, true);",
                  "      for (int b = 0; b < PER_BEAT; ++b) if (keep[b / 8] >> (b % 8) & 1) {",
                  "        if ((size_t)b >= n) { what |= fail(s, label, (\"wrote at \" + hex(q.aw_addr + b) + "
                  "\", outside the messages it was given\").c_str()); break; }",
                  "        ((uint8_t*)q.aw_addr)[b] = data[b]; }",
                  f"      q.aw_addr += PER_BEAT; ++q.writes; what |= 1; int last = t->{p}_wlast ? 1 : 0;",
                  "      if (--q.aw_left == 0) { q.b_pending = true; if (!last) what |= fail(s, label, "
                  "\"WLAST missing on a burst's last beat\"); }",
                  "      else if (last) what |= fail(s, label, \"WLAST before the burst's last beat\"); }",
                  f"    if (t->{p}_arvalid && !q.ar_busy) {{ q.ar_busy = true; q.ar_addr = t->{p}_araddr; "
                  f"q.ar_left = t->{p}_arlen + 1; q.ar_wait = READ_LATENCY;",
                  f"      if (t->{p}_arburst != 1 || t->{p}_arsize != SIZE_LOG2) what |= fail(s, label, "
                  "\"a read burst must be INCR of data-width beats\"); }",
                  "    else if (q.ar_busy && q.ar_wait > 0) --q.ar_wait;",
                  f"    else if (q.ar_busy && t->{p}_rready) {{ q.ar_addr += PER_BEAT; ++q.reads; what |= 1; "
                  "if (--q.ar_left == 0) q.ar_busy = false; } }"]
    for i, port in enumerate(inputs):
        lines += [f"  fired[{i}] = t->{port.prefix}_tvalid && t->{port.prefix}_tready;"]
    for j, port in enumerate(outputs):
        lines += [f"  get(t->{port.prefix}_tdata, data, PER_BEAT); get(t->{port.prefix}_tkeep, keep, KEEP_BYTES);",
                  f"  what |= watch(s, {j}, t->{port.prefix}_tvalid, t->{port.prefix}_tready, data, keep, "
                  f"t->{port.prefix}_tlast ? 1 : 0);"]
    if monitored:
        lines += [f"  static const char* WATCHED[] = {_c_strings([label for label, _ in monitored])};",
                  f"  static const char* BROKEN[] = {_c_strings([rule for _, rule in monitored])};",
                  "  uint64_t broken = (uint64_t)t->hw_violations;",
                  f"  for (int k = 0; k < {len(monitored)}; ++k) if (broken >> k & 1) {{",
                  "    what |= fail(s, WATCHED[k], BROKEN[k]); break; }"]
    lines += ["  (void)fired; (void)data; (void)keep; return what;", "}", "", "static void edge(Sim* s) {"]
    lines += ["  s->top->clk = 1; s->top->eval(); s->top->clk = 0; s->top->eval();" if clocked else "  (void)s;"]
    lines += ["}"]
    return "\n".join(lines) + "\n"


def compile_simulator(verilog: str, top: str, ports: list[StreamPort], data_width: int, clocked: bool,
                      design_key: str, monitored: list[tuple[str, str]] | None = None,
                      sources: list[Path] | None = None, cache: Path | None = None,
                      memories: list[MemoryPort] | None = None) -> Path:
    """The shared library of ``top`` with its harness, compiled once per design (see the module's docstring).

    ``design_key`` identifies the design as its sources do (Amaranth's Verilog of one design may
    order ports and number wires differently from one process to the next, so the text cannot).
    """
    harness = harness_source(top, ports, data_width, clocked, monitored, memories)
    digest = hashlib.sha256(f"{_HARNESS_VERSION}\0{design_key}\0{harness}".encode()).hexdigest()[:20]
    folder = (cache or cache_root()) / f"{top}-{digest}"
    library = folder / f"lib{top}.so"
    if library.exists():
        return library
    verilator = verilator_command()
    build = folder.with_name(folder.name + f".build{os.getpid()}")
    shutil.rmtree(build, ignore_errors=True)
    build.mkdir(parents=True)
    (build / f"{top}.v").write_text(verilog)
    (build / "harness.cpp").write_text(harness)
    jobs = str(max(1, min(4, os.cpu_count() or 1)))
    _run([verilator, "--cc", f"{top}.v", *(str(s) for s in sources or []), "--top-module", top, "-Mdir", "obj",
          "-O3", "--x-assign", "fast",
          "--x-initial", "fast", "--noassert", "-Wno-fatal", "-Wno-lint", "-Wno-style", "-CFLAGS", "-fPIC -O2",
          "--build", "-j", jobs], build, top)
    include = _include_folder(verilator)
    archives = sorted(str(p) for p in (build / "obj").glob("*.a"))
    runtime = _runtime_objects(verilator, include, cache or cache_root())
    _run(["g++", "-shared", "-fPIC", "-O2", "-std=c++17", "-I", "obj", "-I", str(include),
          "-I", str(include / "vltstd"), "harness.cpp", *runtime, *archives, "-pthread", "-o", library.name],
         build, top)
    folder.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.replace(build, folder)  # another launch that compiled the same design first wins; both are equal
    except OSError:
        shutil.rmtree(build, ignore_errors=True)
    return library


def _include_folder(verilator: str) -> Path:
    root = subprocess.run([verilator, "--getenv", "VERILATOR_ROOT"], capture_output=True, text=True, check=False)
    if root.returncode == 0 and root.stdout.strip():
        return Path(root.stdout.strip()) / "include"
    return Path(verilator).resolve().parent.parent / "share" / "verilator" / "include"


def _runtime_objects(verilator: str, include: Path, cache: Path) -> list[str]:
    """Verilator's own runtime, compiled once per Verilator version and machine (most of a design's
    compile time otherwise), then linked into each design's library."""
    version = subprocess.run([verilator, "--version"], capture_output=True, text=True, check=False).stdout
    folder = cache / f"runtime-{hashlib.sha256(version.encode()).hexdigest()[:12]}"
    objects = [folder / f"{name}.o" for name in ("verilated", "verilated_threads")]
    if all(o.exists() for o in objects):
        return [str(o) for o in objects]
    build = folder.with_name(folder.name + f".build{os.getpid()}")
    shutil.rmtree(build, ignore_errors=True)
    build.mkdir(parents=True)
    for target in objects:
        _run(["g++", "-c", "-fPIC", "-O2", "-std=c++17", "-I", str(include), "-I", str(include / "vltstd"),
              str(include / f"{target.stem}.cpp"), "-o", target.name], build, "Verilator's runtime")
    try:
        os.replace(build, folder)
    except OSError:
        shutil.rmtree(build, ignore_errors=True)  # another process built it first: both are equal
    return [str(o) for o in objects]


def _run(command: list[str], cwd: Path, top: str) -> None:
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        tail = "\n".join((done.stderr or done.stdout).strip().splitlines()[-15:])
        raise HardwareError(f"compiling the simulator of {top} failed ({Path(command[0]).name} exited "
                            f"{done.returncode}; the build is in {cwd}):\n{tail}")


class VerilatedTop:
    """One instance of a compiled top: push messages into input ports, run cycles, pop output messages."""

    def __init__(self, library: Path, ports: list[StreamPort]) -> None:
        self._lib = ctypes.CDLL(str(library))
        lib = self._lib
        lib.hs_new.restype = ctypes.c_void_p
        lib.hs_free.argtypes = [ctypes.c_void_p]
        lib.hs_push.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_size_t]
        lib.hs_alloc.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t]
        lib.hs_alloc.restype = ctypes.c_void_p
        lib.hs_front.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.hs_front.restype = ctypes.c_void_p
        lib.hs_drop.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.hs_queued.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.hs_queued.restype = ctypes.c_size_t
        lib.hs_set_limit.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_size_t]
        lib.hs_next_size.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.hs_next_size.restype = ctypes.c_longlong
        lib.hs_pop.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p]
        lib.hs_partial.argtypes = [ctypes.c_void_p, ctypes.c_int]
        lib.hs_partial.restype = ctypes.c_size_t
        lib.hs_cycle.argtypes = [ctypes.c_void_p]
        lib.hs_cycle.restype = ctypes.c_uint64
        lib.hs_error.argtypes = [ctypes.c_void_p]
        lib.hs_error.restype = ctypes.c_char_p
        lib.hs_stats.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.POINTER(ctypes.c_uint64)]
        lib.hs_run.argtypes = [ctypes.c_void_p, ctypes.c_uint64, ctypes.c_uint64]
        lib.hs_allow.argtypes = [ctypes.c_void_p, ctypes.c_uint64, ctypes.c_size_t, ctypes.c_int]
        lib.hs_forbid.argtypes = [ctypes.c_void_p, ctypes.c_uint64]
        lib.hs_mem_stats.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_uint64)]
        self.inputs = [p for p in ports if p.feeds_design]
        self.outputs = [p for p in ports if not p.feeds_design]
        self._handle: int | None = lib.hs_new()

    def _h(self) -> int:
        if self._handle is None:
            raise HardwareError("the simulator is closed")
        return self._handle

    def push(self, port: int, body: bytes) -> None:
        if not body:
            raise HardwareError(f"{self.inputs[port].label}: a message needs at least one byte")
        self._lib.hs_push(self._h(), port, body, len(body))

    def loan_input(self, port: int, size: int) -> memoryview:
        """A message of ``size`` bytes queued at input ``port``, to be written in place (the message is
        encoded straight into the simulator's queue) before the next :meth:`run`."""
        if size < 1:
            raise HardwareError(f"{self.inputs[port].label}: a message needs at least one byte")
        address = self._lib.hs_alloc(self._h(), port, size)
        return memoryview((ctypes.c_ubyte * size).from_address(address)).cast("B")

    def front(self, port: int) -> memoryview | None:
        """The next message output ``port`` ended, in the simulator's memory (no copy): valid until
        :meth:`drop` or the next :meth:`run`; None when there is none."""
        size = self._lib.hs_next_size(self._h(), port)
        if size < 0:
            return None
        address = self._lib.hs_front(self._h(), port)
        return memoryview((ctypes.c_ubyte * size).from_address(address)).cast("B")

    def drop(self, port: int) -> None:
        """Let go of the message :meth:`front` showed."""
        self._lib.hs_drop(self._h(), port)

    def queued(self, port: int) -> int:
        return int(self._lib.hs_queued(self._h(), port))

    def set_output_limit(self, port: int, messages: int) -> None:
        """How many finished messages an output holds before it takes TREADY low (back-pressure)."""
        self._lib.hs_set_limit(self._h(), port, messages)

    def pop(self, port: int) -> bytes | None:
        size = self._lib.hs_next_size(self._h(), port)
        if size < 0:
            return None
        buffer = ctypes.create_string_buffer(max(1, size))
        self._lib.hs_pop(self._h(), port, buffer)
        return buffer.raw[:size]

    def partial(self, port: int) -> int:
        """Bytes an output has received of a message not ended by TLAST yet."""
        return int(self._lib.hs_partial(self._h(), port))

    @property
    def cycle(self) -> int:
        return int(self._lib.hs_cycle(self._h()))

    def stats(self, output: bool, port: int) -> tuple[int, int, int]:
        """``(messages, beats, busy cycles)`` of a port: busy from a message's first beat to its last."""
        into = (ctypes.c_uint64 * 3)()
        self._lib.hs_stats(self._h(), int(output), port, into)
        return int(into[0]), int(into[1]), int(into[2])

    def run(self, max_cycles: int, idle: int) -> int:
        """Run until something needs Python (see ``RunEvents``) or ``max_cycles`` passed."""
        events = int(self._lib.hs_run(self._h(), max_cycles, idle))
        if events & VIOLATION:
            raise HardwareError(self._lib.hs_error(self._h()).decode())
        return events

    def allow(self, address: int, size: int, writable: bool) -> None:
        """Let the hardware's memory ports reach ``size`` bytes at ``address`` (of this process), to read, or to
        read and write; anything else they touch stops the run with an error."""
        self._lib.hs_allow(self._h(), address, size, int(writable))

    def forbid(self, address: int) -> None:
        """Take back the window starting at ``address``."""
        self._lib.hs_forbid(self._h(), address)

    def memory_stats(self, port: int) -> tuple[int, int]:
        """``(beats read, beats written)`` through memory port ``port``."""
        into = (ctypes.c_uint64 * 2)()
        self._lib.hs_mem_stats(self._h(), port, into)
        return int(into[0]), int(into[1])

    def close(self) -> None:
        if self._handle is not None:
            self._lib.hs_free(self._handle)
            self._handle = None


# what a run reports (bits of its result)
BEAT, OUTPUT_ENDED, INPUT_DRY, VIOLATION, IDLE = 1, 2, 4, 8, 16
