// The cycle loop's fixed part, included by hetros.hw._verilator after the constants it generates per design
// (TOP, PER_BEAT, SIZE_LOG2, N_IN, N_OUT, N_MEM, MEM_LABELS, OUT_LABELS, RESET) and before the generated
// drive()/sample() that read and write the design's signals: ports are indices here.
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

// per port: messages, beats, busy cycles (a message's first beat to its last) and, of those, the cycles it waited on
// software (an output's subscriber full held TREADY low, here or downstream): busy - waited is hardware time
struct InPort {
  std::deque<std::vector<uint8_t>> queue; size_t offset = 0;
  uint64_t messages = 0, beats = 0, busy = 0, started = 0, waited = 0;
};
struct OutPort {
  std::vector<uint8_t> current; std::deque<std::vector<uint8_t>> done; size_t limit = 4;
  uint64_t messages = 0, beats = 0, busy = 0, started = 0, waited = 0;
  bool held = false; uint8_t held_data[PER_BEAT]; uint8_t held_keep[KEEP_BYTES]; int held_last = 0;
};
// an AXI4 slave over a simulated physical address space: each window Python allowed is a message's array,
// placed at a physical address (what the hardware sees) and held at a host address (where its bytes are)
struct Window { uint64_t start, end; bool writable; uint8_t* host; };
struct MemPort {
  bool ar_busy = false; uint64_t ar_addr = 0; int ar_left = 0; int ar_wait = 0;
  bool aw_busy = false; uint64_t aw_addr = 0; int aw_left = 0; bool b_pending = false;
  std::string bad; uint64_t reads = 0, writes = 0;
};
static const int READ_LATENCY = 8;
#ifdef TRACE
// --trace: the last cycles as a waveform, written to two files in turn (`window` cycles each) that Python stitches
// together at the end: a run of millions of cycles keeps a bounded file that ends where the run (or the error) did
struct Trace {
  VerilatedVcdC* vcd = nullptr; std::string base; int depth = 99, part = 0;
  uint64_t window = 0, period = 0, began = 0, began_before = 0;
};
#endif
struct Sim {
  VerilatedContext* context; TOP* top;
  InPort in[N_IN > 0 ? N_IN : 1]; OutPort out[N_OUT > 0 ? N_OUT : 1];
  MemPort mem[N_MEM > 0 ? N_MEM : 1]; std::vector<Window> windows;
  uint64_t cycle = 0, waited = 0; std::string error;  // waited: cycles an output's software subscriber was full
  bool held = false;  // this cycle, an output's software subscriber was full
  // seeded random stalls, as a verification harness drives a design: out of 256 cycles, how many an input's
  // TVALID rests between beats and an output's TREADY is low (0: none)
  uint64_t rng = 0; unsigned in_gap = 0, out_gap = 0;
  bool offered[N_IN > 0 ? N_IN : 1] = {};  // an input showed TVALID and was not taken: it must stay up
#ifdef TRACE
  Trace trace;
#endif
};

#ifdef TRACE
static void trace_open(Sim* s) {
  Trace& t = s->trace; t.began_before = t.began; t.began = s->cycle;
  t.vcd->open((t.base + ".part" + std::to_string(t.part) + ".vcd").c_str());
}
// the waveform's time in picoseconds: half a clock period apart, so the clock shows as it toggles
#define TRACE_AT(s, half) do { if ((s)->trace.vcd) \
  (s)->trace.vcd->dump((s)->cycle * (s)->trace.period + (half) * ((s)->trace.period / 2)); } while (0)
static void trace_turn(Sim* s) {
  Trace& t = s->trace;
  if (t.vcd && s->cycle - t.began >= t.window) { t.vcd->close(); t.part ^= 1; trace_open(s); }
}
#else
#define TRACE_AT(s, half) do { (void)(s); } while (0)
static void trace_turn(Sim*) {}
#endif

// xorshift64*: the same stalls for the same seed, on every machine
static unsigned coin(Sim* s) {
  s->rng ^= s->rng >> 12; s->rng ^= s->rng << 25; s->rng ^= s->rng >> 27;
  return (unsigned)((s->rng * 2685821657736338717ull) >> 56);
}
// whether input ``i`` rests this cycle (only between beats it has not offered: TVALID, once up, stays up)
static bool input_rests(Sim* s, int i) { return s->in_gap && !s->offered[i] && coin(s) < s->in_gap; }
static bool output_stalls(Sim* s) { return s->out_gap && coin(s) < s->out_gap; }

// bytes from physical ``address`` (up to ``n``) inside one allowed window, 0 when none holds it; ``*host``
// is where the first of them is
static size_t reachable(Sim* s, uint64_t address, size_t n, bool write, uint8_t** host) {
  for (const Window& w : s->windows)
    if (address >= w.start && address < w.end && (!write || w.writable)) {
      *host = w.host + (address - w.start);
      return (size_t)(w.end - address) < n ? (size_t)(w.end - address) : n; }
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
  trace_turn(s);
  bool held = false;  // software holds an output back this cycle (the gateway's queue for its subscriber is full)
  for (int j = 0; j < N_OUT; ++j) {
    OutPort& p = s->out[j]; bool full = p.done.size() >= p.limit; held |= full;
    if (full && !p.current.empty()) ++p.waited; }
  if (held) ++s->waited;
  s->held = held;
  drive(s); s->top->eval(); TRACE_AT(s, 0);
  int what = sample(s, fired);
  edge(s);
  for (int i = 0; i < N_IN; ++i) {
    if (fired[i]) { what |= taken(s, i); s->offered[i] = false; }
    else if (held && s->in[i].offset > 0) ++s->in[i].waited;  // a message half in, stalled by a held output
  }
  ++s->cycle; return what;
}

extern "C" {
void* hs_new() {
  Sim* s = new Sim; s->context = new VerilatedContext;
#ifdef TRACE
  s->context->traceEverOn(true);
#endif
  s->top = new TOP{s->context};
  RESET;
  return s;
}
// start the waveform (a simulator compiled without TRACE answers 0): files base.part0.vcd and base.part1.vcd,
// `window` cycles each, `period` picoseconds a cycle, `depth` levels of the design (1: the top's ports only)
int hs_trace(void* h, const char* base, uint64_t window, uint64_t period, int depth) {
#ifdef TRACE
  Sim* s = (Sim*)h; Trace& t = s->trace;
  if (t.vcd) return 1;
  t.vcd = new VerilatedVcdC; t.base = base; t.window = window ? window : 1; t.period = period ? period : 2;
  t.depth = depth; if (depth < 99) t.vcd->dumpvars(depth, "TOP");  // as Verilog's $dumpvars(depth, TOP)
  s->top->trace(t.vcd, 99); trace_open(s); t.began_before = s->cycle;
  return 1;
#else
  (void)h; (void)base; (void)window; (void)period; (void)depth; return 0;
#endif
}
// close the waveform's files: [the part written last, the cycle it began at, the cycle the other part began at]
void hs_trace_close(void* h, uint64_t* into) {
#ifdef TRACE
  Trace& t = ((Sim*)h)->trace;
  if (t.vcd) { t.vcd->close(); delete t.vcd; t.vcd = nullptr; }
  into[0] = (uint64_t)t.part; into[1] = t.began; into[2] = t.began_before;
#else
  (void)h; into[0] = into[1] = into[2] = 0;
#endif
}
void hs_allow(void* h, uint64_t physical, uint8_t* host, size_t size, int writable) {
  ((Sim*)h)->windows.push_back(Window{physical, physical + size, writable != 0, host}); }
void hs_forbid(void* h, uint64_t start) {
  std::vector<Window>& w = ((Sim*)h)->windows;
  for (size_t i = w.size(); i-- > 0;) if (w[i].start == start) w.erase(w.begin() + i); }
void hs_mem_stats(void* h, int port, uint64_t* into) {
  Sim* s = (Sim*)h; into[0] = s->mem[port].reads; into[1] = s->mem[port].writes; }
void hs_stalls(void* h, uint64_t seed, unsigned in_gap, unsigned out_gap) {
  Sim* s = (Sim*)h; s->rng = seed * 0x9E3779B97F4A7C15ull | 1; s->in_gap = in_gap; s->out_gap = out_gap; }
void hs_free(void* h) {
  Sim* s = (Sim*)h;
#ifdef TRACE
  if (s->trace.vcd) { s->trace.vcd->close(); delete s->trace.vcd; }
#endif
  s->top->final(); delete s->top; delete s->context; delete s; }
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
  if (output) { OutPort& p = s->out[port]; into[0] = p.messages; into[1] = p.beats; into[2] = p.busy; into[3] = p.waited; }
  else { InPort& p = s->in[port]; into[0] = p.messages; into[1] = p.beats; into[2] = p.busy; into[3] = p.waited; }
}
uint64_t hs_waited(void* h) { return ((Sim*)h)->waited; }
// up to max_cycles; ends early on an event Python must handle, after idle quiet cycles with no input waiting, or
// after HELD_QUIET quiet cycles with an output held back by software (its subscriber must take before much moves:
// simulating on would only count cycles of waiting)
static const uint64_t HELD_QUIET = 256;
int hs_run(void* h, uint64_t max_cycles, uint64_t idle) {
  Sim* s = (Sim*)h; int seen = 0; uint64_t quiet = 0, still = 0;
  for (uint64_t n = 0; n < max_cycles; ++n) {
    int what = cycle(s); seen |= what;
    if (what & 14) return seen;
    if (what & 1) { quiet = still = 0; continue; }
    if (s->held && ++still >= HELD_QUIET) return seen | 16;
    bool waiting = false;
    for (int i = 0; i < N_IN; ++i) waiting |= !s->in[i].queue.empty();
    if (!waiting && ++quiet >= idle) return seen | 16;
  }
  return seen;
}
}

