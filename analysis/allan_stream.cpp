// The one-pass Allan-family engine (see allan_engine.hpp for the design).
#include <algorithm>
#include <array>
#include <atomic>
#include <barrier>
#include <bit>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "analysis/allan_engine.hpp"
#include "analysis/drift.hpp"
#include "analysis/allan_kernels.hpp"
#include "analysis/huge_buffer.hpp"

namespace rig::analysis {

std::size_t SpanSource::read_at(std::uint64_t pos, std::span<double> out) const {
  if (pos >= v_.size()) return 0;
  const std::size_t n = std::min<std::size_t>(out.size(), v_.size() - pos);
  std::copy_n(v_.begin() + static_cast<std::ptrdiff_t>(pos), n, out.begin());
  return n;
}

namespace detail {
namespace {

constexpr std::size_t kCheckpointEvery = 4096;  // P checkpoints for random access (frequency data)

using namespace kernels;  // allan_kernels.hpp

// ---------------------------------------------------------------------------------------------
struct PhaseState {
  double C = 0;  // C_k of the block holding the next index
  double L = 0;  // L(next index)
};

struct Acc {
  Deviation type{};
  std::size_t m = 0;
  std::size_t span = 0;   // highest phase offset of a term relative to its base
  std::size_t nwin = 0;   // windows (offsets 0, m, 2m[, 3m])
  std::size_t bases = 0;  // term bases 0..bases-1 (stride m for ADEV/HDEV)
  double sum = 0;
  std::size_t terms = 0;
  double inner = 0;       // MDEV state: the window sum at the next base
  bool primed = false;    // MDEV: `inner` holds the window sum of this accumulator's next base
  bool far = false;       // post-pass: even the newer windows do not fit the ring
  // TOTDEV: the index of the OADEV accumulator with the same m, whose sum is this one's interior
  // (SP 1065 eq. 25's terms with i - m >= 0 and i + m <= N - 1 are OADEV's, eq. 11): the pass runs
  // them once, and only the reflected edges are this accumulator's own work. npos: run its own.
  static constexpr std::size_t kOwnInterior = static_cast<std::size_t>(-1);
  std::size_t interior_of = kOwnInterior;
  // In-pass cursors: the oldest `cursors` windows (P[b], and P[b + m] when that is beyond the
  // ring too) rebuilt by sequential cursors; the newer ones read from the ring.
  struct Cursor {
    std::uint64_t next = 0;  // the next phase index it builds, and the builder's state there
    PhaseState state;
    bool started = false;
    std::vector<double> buf, scratch;
  };
  static constexpr std::size_t kMaxCursors = 2;
  std::size_t cursors = 0;
  Cursor cur[kMaxCursors];

  bool strided() const { return type == Deviation::ADEV || type == Deviation::HDEV; }
  bool modified() const { return type == Deviation::MDEV || type == Deviation::TDEV; }

  // Terms with base in [b0, b0 + len); w[k] = &P[b0 + k m], contiguous for len points.
  void run(std::size_t b0, std::size_t len, const double* const* w) {
    if (strided()) {
      const std::size_t t = (b0 % m == 0) ? 0 : m - b0 % m;
      if (t >= len) return;
      if (m == 1) sum += nwin == 3 ? sum_d2(w[0], w[1], w[2], len) : sum_d3(w[0], w[1], w[2], w[3], len);
      else if (nwin == 3) sum += sum_d2_strided(w[0], w[1], w[2], t, m, len);
      else sum += sum_d3_strided(w[0], w[1], w[2], w[3], t, m, len);
      terms += (len - t + m - 1) / m;
      return;
    }
    if (modified()) sum += mdev_run(w[0], w[1], w[2], w[3], len, m, inner);
    else if (nwin == 3) sum += sum_d2(w[0], w[1], w[2], len);
    else sum += sum_d3(w[0], w[1], w[2], w[3], len);
    terms += len;
  }
};

Acc make_acc(Deviation type, std::size_t m, std::size_t n) {
  Acc a;
  a.type = type;
  a.m = m;
  const auto sub = [](std::size_t x, std::size_t y) { return x > y ? x - y : 0; };
  switch (type) {
    case Deviation::ADEV:
    case Deviation::OADEV:
    case Deviation::TOTDEV:  // interior terms; the reflected edges are added afterwards
      a.span = 2 * m;
      a.nwin = 3;
      a.bases = sub(n, 2 * m);
      break;
    case Deviation::HDEV:
    case Deviation::OHDEV:
      a.span = 3 * m;
      a.nwin = 4;
      a.bases = sub(n, 3 * m);
      break;
    case Deviation::MDEV:
    case Deviation::TDEV:
      a.span = 3 * m;
      a.nwin = 4;
      a.bases = sub(n, 3 * m);  // plus the prologue term
      break;
  }
  return a;
}

// ---------------------------------------------------------------------------------------------
// Frequency data: P is built in blocks of kCheckpointEvery points, P[j] = C_k + L(j) with
// C_k = P[k B] (the checkpoint) and L(j) the running sum of (y - c) from the block's start.
// Every path (main pass, cursors, random access) computes each L from its block start in the
// same order, so they agree to the bit; four blocks at a time run as independent chains, so
// the running sum is not one long chain of dependent additions.
// P[j0, j0 + len) into out; y holds y[j0 .. j0 + ny) (ny = len, or len - 1 at the record's end).
void phase_run(const double* y, std::size_t len, std::size_t ny, std::uint64_t j0, double c, PhaseState& st,
               double* out) {
  constexpr std::size_t B = kCheckpointEvery;
  std::size_t t = 0;
  auto scalar_to = [&](std::size_t stop) {
    for (; t < stop; ++t) {
      const std::uint64_t j = j0 + t;
      if (j % B == 0 && j != 0) st.C = st.C + st.L, st.L = 0;
      out[t] = st.C + st.L;
      if (t < ny) st.L = st.L + (y[t] - c);
    }
  };
  // Up to the first block boundary (a boundary at j0 itself is handled by the 4-block path).
  const std::size_t to_boundary = static_cast<std::size_t>((B - j0 % B) % B);
  scalar_to(std::min(len, to_boundary));
  while (t + 4 * B <= ny) {  // four whole blocks with all their y
    if (j0 + t != 0) st.C = st.C + st.L, st.L = 0;
    double l0 = 0, l1 = 0, l2 = 0, l3 = 0;
    const double *y0 = y + t, *y1 = y0 + B, *y2 = y1 + B, *y3 = y2 + B;
    double *o0 = out + t, *o1 = o0 + B, *o2 = o1 + B, *o3 = o2 + B;
    for (std::size_t i = 0; i < B; ++i) {
      o0[i] = l0, o1[i] = l1, o2[i] = l2, o3[i] = l3;
      l0 = l0 + (y0[i] - c), l1 = l1 + (y1[i] - c), l2 = l2 + (y2[i] - c), l3 = l3 + (y3[i] - c);
    }
    const double C0 = st.C, C1 = C0 + l0, C2 = C1 + l1, C3 = C2 + l2;
    for (std::size_t i = 0; i < B; ++i) o0[i] = C0 + o0[i], o1[i] = C1 + o1[i], o2[i] = C2 + o2[i], o3[i] = C3 + o3[i];
    st.C = C3, st.L = l3;  // state at the start of the next block, before its boundary step
    t += 4 * B;
    // the next boundary step (C += L) happens at the top of the loop or in scalar_to
  }
  scalar_to(len);
}

// The builder's state at phase index s (a multiple of kCheckpointEvery, s <= the values in y)
// without writing P: each block's total L, summed as phase_run sums it (one chain of additions
// from 0 per block: four blocks interleaved for their latency, each in its own order), and the
// checkpoints C_{k+1} = C_k + L_k in order. Bit for bit the state phase_run reaches at s.
PhaseState phase_state_at(const double* y, std::uint64_t s, double c) {
  constexpr std::size_t B = kCheckpointEvery;
  const std::uint64_t blocks = s / B;
  if (blocks == 0) return {};
  std::vector<double> tot(blocks);
  std::uint64_t k = 0;
  for (; k + 4 <= blocks; k += 4) {
    const double *y0 = y + k * B, *y1 = y0 + B, *y2 = y1 + B, *y3 = y2 + B;
    double l0 = 0, l1 = 0, l2 = 0, l3 = 0;
    for (std::size_t i = 0; i < B; ++i)
      l0 = l0 + (y0[i] - c), l1 = l1 + (y1[i] - c), l2 = l2 + (y2[i] - c), l3 = l3 + (y3[i] - c);
    tot[k] = l0, tot[k + 1] = l1, tot[k + 2] = l2, tot[k + 3] = l3;
  }
  for (; k < blocks; ++k) {
    double l = 0;
    for (std::size_t i = 0; i < B; ++i) l = l + (y[k * B + i] - c);
    tot[k] = l;
  }
  PhaseState st;  // at s: C of the last whole block and its total, before the boundary step
  for (std::uint64_t b = 0; b + 1 < blocks; ++b) st.C = st.C + tot[b];
  st.L = tot[blocks - 1];
  return st;
}

// Builds P from the source, sequentially (main pass) or from a checkpoint (random access).
class PhaseBuilder {
 public:
  PhaseBuilder(const ChunkSource& src, PhaseSpec spec) : src_(src), spec_(spec) {}
  const PhaseSpec& spec() const { return spec_; }

  // Sequential: P[j] for j in [j0, j0 + out.size()), continuing from the state at j0.
  void sequential(std::uint64_t j0, std::span<double> out, PhaseState& st, std::vector<double>& scratch) const {
    if (spec_.kind == DataKind::Phase) {
      pointwise(j0, out, scratch);
      return;
    }
    if (out.empty()) return;
    const std::size_t ny = static_cast<std::size_t>(std::min<std::uint64_t>(out.size(), spec_.n_src - j0));
    const double* y = src_.contiguous();
    if (y) {
      y += j0;
    } else {
      scratch.resize(ny);
      fill(j0, std::span<double>(scratch.data(), ny));
      y = scratch.data();
    }
    phase_run(y, out.size(), ny, j0, spec_.shift, st, out.data());
  }

  // Random access: P[lo, lo + out.size()) using the checkpoints (frequency data).
  void range(std::uint64_t lo, std::span<double> out, const std::vector<double>& checkpoints,
             std::vector<double>& scratch) const {
    if (spec_.kind == DataKind::Phase) {
      pointwise(lo, out, scratch);
      return;
    }
    PhaseState st = state_at(lo, checkpoints, scratch);
    sequential(lo, out, st, scratch);
  }

  // The builder's state at phase index lo (frequency data): its block's checkpoint and L(lo)
  // from the block's start, in the main pass's order. The checkpoint must exist; the main pass
  // may be appending later ones meanwhile (the vector is reserved: it never moves).
  PhaseState state_at(std::uint64_t lo, const std::vector<double>& checkpoints, std::vector<double>& scratch) const {
    if (spec_.kind == DataKind::Phase) return {};
    const std::uint64_t cp = lo / kCheckpointEvery;
    PhaseState st{checkpoints.data()[cp], 0};
    const std::uint64_t j = cp * kCheckpointEvery;
    if (j < lo) {
      scratch.resize(lo - j);
      fill(j, scratch);
      for (double y : scratch) st.L = st.L + (y - spec_.shift);
    }
    return st;
  }

 private:
  void fill(std::uint64_t pos, std::span<double> out) const {
    std::size_t got = 0;
    while (got < out.size()) {
      const std::size_t r = src_.read_at(pos + got, out.subspan(got));
      if (r == 0) throw std::runtime_error("allan: source ended at value " + std::to_string(pos + got) + " of " +
                                           std::to_string(spec_.n_src));
      got += r;
    }
  }
  void pointwise(std::uint64_t j0, std::span<double> out, std::vector<double>& scratch) const {
    scratch.resize(out.size());
    fill(j0, scratch);
    for (std::size_t t = 0; t < out.size(); ++t)
      out[t] = (scratch[t] - spec_.x0 - spec_.slope * static_cast<double>(j0 + t)) * spec_.rate_hz;
  }

  const ChunkSource& src_;
  PhaseSpec spec_;
};

PhaseSpec make_spec(const ChunkSource& src, DataKind kind, double rate_hz) {
  PhaseSpec s;
  s.kind = kind;
  s.rate_hz = rate_hz;
  s.n_src = src.size();
  s.n = kind == DataKind::Frequency ? s.n_src + 1 : s.n_src;
  if (s.n_src == 0) return s;
  if (kind == DataKind::Frequency) {
    std::vector<double> head(std::min<std::uint64_t>(s.n_src, 4096));
    const std::size_t got = src.read_at(0, head);
    double sum = 0;
    for (std::size_t i = 0; i < got; ++i) sum += head[i];
    s.shift = got ? sum / static_cast<double>(got) : 0;
  } else {
    double a = 0, b = 0;
    src.read_at(0, std::span<double>(&a, 1));
    src.read_at(s.n_src - 1, std::span<double>(&b, 1));
    s.x0 = a;
    s.slope = s.n_src > 1 ? (b - a) / static_cast<double>(s.n_src - 1) : 0;
  }
  return s;
}

// The ring of the most recent phase points (P[j] at j mod capacity).
struct Ring {
  // Not zero-filled (every slot is written before it is read); transparent huge pages where the
  // kernel offers them: the lag windows of the long taus are far apart, so 4 KiB pages would
  // cost a TLB walk every 512 points of every stream.
  detail::HugeBuffer mem;
  std::size_t size = 0;

  void allocate(std::size_t points) {
    mem = detail::huge_buffer(points);
    size = points;
  }
  double* at(std::uint64_t j) { return mem.get() + (j % size); }
  std::size_t room(std::uint64_t j) const { return size - static_cast<std::size_t>(j % size); }
};

// Runs acc over bases [b0, b1) with windows read from the ring, split where a window wraps.
void run_from_ring(Acc& a, Ring& ring, std::uint64_t b0, std::uint64_t b1) {
  const double* w[4];
  while (b0 < b1) {
    std::size_t len = b1 - b0;
    for (std::size_t k = 0; k < a.nwin; ++k) len = std::min(len, ring.room(b0 + k * a.m));
    for (std::size_t k = 0; k < a.nwin; ++k) w[k] = ring.at(b0 + k * a.m);
    a.run(b0, len, w);
    b0 += len;
  }
}

// A doubling chain of OADEV/TOTDEV accumulators (ascending, m_{i+1} = 2 m_i, all in the ring)
// over the heads [hi, hi2): member i has terms from h = span_i = 2 m_i on, so between span_i and
// span_{i+1} the first i + 1 members run fused.
void run_chain(Acc* const* chain, int k, Ring& ring, std::uint64_t hi, std::uint64_t hi2) {
  const std::size_t m0 = chain[0]->m;
  const double* lag[kMaxChain + 1];
  double part[kMaxChain];
  for (int active = 1; active <= k; ++active) {
    const std::uint64_t lo = std::max<std::uint64_t>(hi, chain[active - 1]->span);
    const std::uint64_t top = active < k ? std::min<std::uint64_t>(hi2, chain[active]->span) : hi2;
    for (std::uint64_t h = lo; h < top;) {
      std::size_t len = std::min<std::uint64_t>(top - h, ring.room(h));
      for (int j = 0; j <= active; ++j) len = std::min(len, ring.room(h - (std::uint64_t{m0} << j)));
      for (int j = 0; j <= active; ++j) lag[j] = ring.at(h - (std::uint64_t{m0} << j));
      std::fill_n(part, active, 0.0);
      chain_d2(active, ring.at(h), lag, len, part);
      for (int i = 0; i < active; ++i) chain[i]->sum += part[i], chain[i]->terms += len;
      h += len;
    }
  }
}

// The same for a doubling chain of OHDEV accumulators (span 3 m_i).
void run_chain3(Acc* const* chain, int k, Ring& ring, std::uint64_t hi, std::uint64_t hi2) {
  const std::size_t m0 = chain[0]->m;
  const double* lag2[kMaxChain + 1];
  const double* lag3[kMaxChain];
  double part[kMaxChain];
  for (int active = 1; active <= k; ++active) {
    const std::uint64_t lo = std::max<std::uint64_t>(hi, chain[active - 1]->span);
    const std::uint64_t top = active < k ? std::min<std::uint64_t>(hi2, chain[active]->span) : hi2;
    for (std::uint64_t h = lo; h < top;) {
      std::size_t len = std::min<std::uint64_t>(top - h, ring.room(h));
      for (int j = 0; j <= active; ++j) len = std::min(len, ring.room(h - (std::uint64_t{m0} << j)));
      for (int j = 0; j < active; ++j) len = std::min(len, ring.room(h - 3 * (std::uint64_t{m0} << j)));
      for (int j = 0; j <= active; ++j) lag2[j] = ring.at(h - (std::uint64_t{m0} << j));
      for (int j = 0; j < active; ++j) lag3[j] = ring.at(h - 3 * (std::uint64_t{m0} << j));
      std::fill_n(part, active, 0.0);
      chain_d3(active, ring.at(h), lag2, lag3, len, part);
      for (int i = 0; i < active; ++i) chain[i]->sum += part[i], chain[i]->terms += len;
      h += len;
    }
  }
}

// A cursor accumulator over the heads [hi, hi2): its oldest windows from its cursors (each built
// sequentially, exactly as the main pass builds the ring, from its start k m on, whose state
// state_at gives), the newer windows from the ring. prime(a) runs before its first term (MDEV:
// the first window sum, by random access to P[0, 3m), all of it built by then).
template <class Builder, class StateAt, class Prime>
void run_cursor(Acc& a, Ring& ring, const Builder& builder, StateAt&& state_at, Prime&& prime, std::uint64_t hi,
                std::uint64_t hi2) {
  const std::uint64_t h0 = std::max<std::uint64_t>(hi, a.span);
  if (h0 >= hi2) return;
  std::uint64_t b0 = h0 - a.span;
  const std::uint64_t b1 = std::min<std::uint64_t>(hi2 - a.span, a.bases);
  if (b0 >= b1) return;
  const std::size_t n = static_cast<std::size_t>(b1 - b0);
  // The cursors only move forward: the bases of successive chunks are contiguous from 0.
  for (std::size_t k = 0; k < a.cursors; ++k) {
    Acc::Cursor& c = a.cur[k];
    if (!c.started) {
      c.next = b0 + k * a.m;
      c.state = state_at(c.next);
      c.started = true;
    }
    c.buf.resize(n);
    builder.sequential(c.next, std::span<double>(c.buf.data(), n), c.state, c.scratch);
    c.next += n;
  }
  if (!a.primed) {
    prime(a);
    a.primed = true;
  }
  const double* w[4];
  for (std::size_t off = 0; off < n;) {
    std::size_t len = n - off;
    for (std::size_t k = a.cursors; k < a.nwin; ++k) len = std::min(len, ring.room(b0 + off + k * a.m));
    for (std::size_t k = 0; k < a.nwin; ++k)
      w[k] = k < a.cursors ? a.cur[k].buf.data() + off : ring.at(b0 + off + k * a.m);
    a.run(b0 + off, len, w);
    off += len;
  }
}

// MDEV's first term: the window sum of d[0..m-1] (P[0..3m-1]), in blocks of `block` points,
// each block's sum from sum_second_diff. read_block(i, len) gives the three windows' pointers
// &P[i], &P[i + m], &P[i + 2m] for len points; every path sums the same blocks in the same order,
// so streamed and in-memory runs agree to the bit.
template <class ReadBlock>
void mdev_prime_first(Acc& a, ReadBlock&& read_block, std::size_t block) {
  double inner = 0;
  for (std::size_t i = 0; i < a.m; i += block) {
    const std::size_t len = std::min(block, a.m - i);
    const auto [p0, p1, p2] = read_block(i, len);
    inner += sum_second_diff(p0, p1, p2, len);
  }
  a.inner = inner;
  a.sum += inner * inner;
  a.terms += 1;
}

// The same from any random-access reader of P (copies the three windows block by block).
template <class ReadP>
void mdev_prologue(Acc& a, ReadP&& read, std::size_t block) {
  std::vector<double> p0, p1, p2;
  mdev_prime_first(a, [&](std::size_t i, std::size_t len) {
    p0.resize(len), p1.resize(len), p2.resize(len);
    read(i, std::span<double>(p0));
    read(i + a.m, std::span<double>(p1));
    read(i + 2 * a.m, std::span<double>(p2));
    return std::array<const double*, 3>{p0.data(), p1.data(), p2.data()};
  }, block);
}

// TOTDEV's reflected edge terms (NIST SP 1065 eq. 25: x*(1-j) = 2x(1) - x(1+j), x*(N+j) = 2x(N) - x(N-j)).
// view(lo, len, buf) gives &P[lo] for len points: in place when the ring holds the record (the
// copies were 18 % of a TOTDEV run), else read into buf.
//
// On each side the reflected point of term i is P[S - i] with S - i in the side's own range
// [lo, hi) (S = lo + hi - 1): a block of terms [a, a + len) reads as its reflection the points
// that the mirror block [S - a - len + 1, S - a + 1) reads as its centres. Blocks are taken in
// such pairs from both ends, so each centre block is read once and serves twice (4 reads per
// two blocks instead of 6: random access rebuilds P from the checkpoints, most of a streamed
// TOTDEV); the middle, shorter than two blocks, block by block.
template <class View>
void totdev_edges(Acc& a, std::uint64_t n, View&& view, std::size_t block) {
  const std::size_t m = a.m;
  std::vector<double> b0, b1, b2, b3;
  const double first = *view(0, 1, b0);
  const double last = *view(n - 1, 1, b0);
  // One side: terms i in [lo, hi), the far neighbour P[i + f_off] (f_off = +m left, -m right).
  auto side = [&](std::uint64_t lo, std::uint64_t hi, std::int64_t f_off, auto&& kernel) {
    const std::uint64_t S = lo + hi - 1;
    auto far = [&](std::uint64_t i) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(i) + f_off); };
    std::uint64_t x = lo, y = hi;  // terms [x, y) not yet summed; S - x + 1 == y throughout
    while (y - x >= 2 * static_cast<std::uint64_t>(block)) {
      const std::uint64_t x2 = y - block;  // the mirror block of [x, x + block)
      const double* c = view(x, block, b0);
      const double* c2 = view(x2, block, b1);
      const double* f = view(far(x), block, b2);
      const double* f2 = view(far(x2), block, b3);
      a.sum += kernel(c2, c, f, block);
      a.sum += kernel(c, c2, f2, block);
      a.terms += 2 * block;
      x += block, y -= block;
    }
    for (std::uint64_t i = x; i < y; i += block) {
      const std::size_t len = static_cast<std::size_t>(std::min<std::uint64_t>(block, y - i));
      const double* r = view(S - i - (len - 1), len, b0);  // P[S-i-len+1 .. S-i], used reversed
      const double* c = view(i, len, b1);
      const double* f = view(far(i), len, b2);
      a.sum += kernel(r, c, f, len);
      a.terms += len;
    }
  };
  const auto sm = static_cast<std::int64_t>(m);
  // Left: i in [1, m-1]: 2P0 - P[m-i] - 2P[i] + P[i+m].
  side(1, m, sm, [&](const double* r, const double* c, const double* f, std::size_t len) {
    return sum_reflected_left(2 * first, r, c, f, len);
  });
  // Right: i in [n-m, n-2]: P[i-m] - 2P[i] + 2P[n-1] - P[2(n-1) - i - m].
  side(n - m, n - 1, -sm, [&](const double* r, const double* c, const double* f, std::size_t len) {
    return sum_reflected_right(2 * last, r, c, f, len);
  });
}

}  // namespace

// Groups the accumulators of one chunk into work items for the cores. Same-type pairs m, 2m,
// 4m ... share windows (tau m reads P at b + m and b + 2m, tau 2m at b + 2m and b + 4m), so a
// doubling chain run in ascending order finds one of its two far windows still in L2: about
// half the memory traffic of independent taus (run_chain fuses them). Chains are cut at kMaxChain.
std::vector<std::vector<std::size_t>> work_items(const std::vector<Acc>& accs, std::vector<std::size_t> idx) {
  std::sort(idx.begin(), idx.end(), [&](std::size_t x, std::size_t y) {
    return accs[x].type != accs[y].type ? accs[x].type < accs[y].type : accs[x].m < accs[y].m;
  });
  std::vector<bool> used(accs.size(), false);
  std::vector<std::vector<std::size_t>> items;
  for (std::size_t i : idx) {
    if (used[i]) continue;
    std::vector<std::size_t> chain{i};
    used[i] = true;
    for (std::size_t cur = i;;) {
      std::size_t nxt = accs.size();
      for (std::size_t j : idx)
        if (!used[j] && accs[j].type == accs[cur].type && accs[j].m == 2 * accs[cur].m) nxt = j;
      if (nxt == accs.size()) break;
      used[nxt] = true;
      chain.push_back(nxt);
      cur = nxt;
    }
    for (std::size_t k = 0; k < chain.size(); k += kMaxChain)
      items.emplace_back(chain.begin() + static_cast<std::ptrdiff_t>(k),
                         chain.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(chain.size(), k + kMaxChain)));
  }
  auto cost = [&](const std::vector<std::size_t>& it) {
    std::uint64_t c = 0;
    for (std::size_t i : it) c += (accs[i].modified() ? 2 : 1) * accs[i].bases;
    return c;
  };
  std::sort(items.begin(), items.end(), [&](const auto& a, const auto& b) { return cost(a) > cost(b); });
  return items;
}

// The sum of P over the pass, for the record's drift (drift.hpp). Each kCheckpointEvery-point
// block is summed on its own (eight chains, so the additions do not wait on one another) while
// the pass has it in cache, and the blocks are added in order with compensation (Neumaier) after
// the pass. A block is summed in one piece whenever the pieces start on block boundaries (the
// default chunk is a multiple of the block and the two-thread build splits at one), so the sum
// is the same bits on one thread or two.
struct PhaseSums {
  std::vector<double> block;
  void reset(std::uint64_t n) { block.assign(static_cast<std::size_t>(n / kCheckpointEvery + 1), 0.0); }
  void add(std::uint64_t j0, const double* p, std::size_t len) {
    for (std::size_t t = 0; t < len;) {
      const std::uint64_t j = j0 + t;
      const std::size_t piece = static_cast<std::size_t>(std::min<std::uint64_t>(len - t, kCheckpointEvery - j % kCheckpointEvery));
      double a[8] = {};
      std::size_t i = 0;
      for (; i + 8 <= piece; i += 8)
        for (std::size_t k = 0; k < 8; ++k) a[k] += p[t + i + k];
      for (; i < piece; ++i) a[0] += p[t + i];
      block[static_cast<std::size_t>(j / kCheckpointEvery)] += ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7]));
      t += piece;
    }
  }
  double total() const {
    CompensatedSum s;
    for (const double x : block) s.add(x);
    return s.value();
  }
};

struct Engine::Impl {
  Impl(const ChunkSource& s, DataKind kind, double rate_hz, const StreamOptions& o, unsigned th, std::size_t c)
      : src(s), spec(make_spec(s, kind, rate_hz)), builder(s, spec), so(o),
        threads(th ? th : std::max(1u, std::thread::hardware_concurrency())), cap(c),
        chunk(std::max<std::size_t>(o.chunk, 1024)) {}

  const ChunkSource& src;
  PhaseSpec spec;
  PhaseBuilder builder;
  StreamOptions so;
  unsigned threads;
  std::size_t cap, chunk;
  void poll() const {
    if (so.poll) so.poll();
  }
  Ring ring;
  bool ring_holds_all = false;
  std::vector<double> checkpoints;

  // State of one run(): the accumulators, their work items, the noise-ID series (one per
  // distinct m) and the phase builder's position.
  std::vector<Acc> accs;
  std::vector<std::vector<std::size_t>> items;
  std::map<std::size_t, std::vector<double>> decim;
  std::vector<double> scratch;
  PhaseState prev;
  PhaseSums phase_sums;   // the pass's sum of P, per block (each build part writes its own blocks)
  double phase_last = 0;  // P[n - 1]

  // Random access to P after the pass: from the ring where it still holds the range (all of P
  // in memory; the record's last ring.size points when streamed: TOTDEV's right edges), else
  // rebuilt from the checkpoints. Both give the same bits.
  auto reader(std::vector<double>& sc) {
    return [this, &sc](std::uint64_t lo, std::span<double> out) {
      const std::uint64_t ring_from = spec.n > ring.size ? spec.n - ring.size : 0;
      if (ring_holds_all || lo >= ring_from) {
        for (std::size_t got = 0; got < out.size();) {  // at most two pieces (the ring wraps)
          const std::size_t len = std::min<std::uint64_t>(out.size() - got, ring.room(lo + got));
          std::copy_n(ring.at(lo + got), len, out.begin() + static_cast<std::ptrdiff_t>(got));
          got += len;
        }
      } else {
        builder.range(lo, out, checkpoints, sc);
      }
    };
  }

  // A (type, m) pair that did not fit the ring: windows rebuilt block by block.
  void run_far(Acc& a) {
    std::vector<double> sc;
    auto read = reader(sc);
    if (a.modified()) mdev_prologue(a, read, chunk);
    std::vector<std::vector<double>> win(a.nwin, std::vector<double>(chunk));
    const double* w[4];
    for (std::uint64_t b = 0; b < a.bases; b += chunk) {
      poll();
      const std::size_t len = std::min<std::uint64_t>(chunk, a.bases - b);
      for (std::size_t j = 0; j < a.nwin; ++j) {
        read(b + j * a.m, std::span<double>(win[j].data(), len));
        w[j] = win[j].data();
      }
      a.run(b, len, w);
    }
  }

  // MDEV/TDEV of a record of exactly 3m phase points: one term, the prologue's, and no base
  // after it for a pass to prime it from (its sum was 0 over 0 terms: NaN, a review).
  bool lone_mdev_term(const Acc& a) const { return a.modified() && !a.primed && a.bases == 0 && spec.n >= 3 * a.m; }

  void finish(Acc& a) {
    std::vector<double> sc;
    if (lone_mdev_term(a)) {
      mdev_prologue(a, reader(sc), chunk);
      a.primed = true;
    }
    if (a.far && a.bases > 0) {
      if (ring_holds_all) {
        if (a.modified())
          mdev_prime_first(a, [&](std::size_t i, std::size_t) {
            return std::array<const double*, 3>{ring.at(i), ring.at(i + a.m), ring.at(i + 2 * a.m)};
          }, chunk);
        const double* w[4];
        for (std::size_t j = 0; j < a.nwin; ++j) w[j] = ring.at(j * a.m);
        a.run(0, a.bases, w);
      } else {
        run_far(a);
      }
    }
    if (a.type == Deviation::TOTDEV && a.m > 1) {
      auto read = reader(sc);
      totdev_edges(a, spec.n, [&](std::uint64_t lo, std::size_t len, std::vector<double>& buf) -> const double* {
        if (ring_holds_all) return ring.at(lo);
        buf.resize(len);
        read(lo, std::span<double>(buf));
        return buf.data();
      }, 4 * chunk);  // longer blocks: each random read rebuilds P from a checkpoint up to 4095 points back
    }
  }

  // The source values under phase points [j, j + len), checked before the pass uses them
  // (ChunkSource::check_range; frequency data has one value fewer than phase points).
  void check_source(std::uint64_t j, std::size_t len) const {
    if (j < spec.n_src) src.check_range(j, static_cast<std::size_t>(std::min<std::uint64_t>(len, spec.n_src - j)));
  }

  void plan(const std::vector<EngineRequest>& req, EngineResult& res);
  void produce(std::uint64_t lo, std::uint64_t hi);
  void run_item(const std::vector<std::size_t>& item, std::vector<Acc>& a_set, std::uint64_t hi, std::uint64_t hi2);
  void run_in_memory();
  void build_in_memory();
  void run_streaming();
  void collect(EngineResult& res);
  EngineResult run(const std::vector<EngineRequest>& req);
};

Engine::Engine(const ChunkSource& src, DataKind kind, double rate_hz, const StreamOptions& so, unsigned threads,
               std::size_t noise_id_cap)
    : impl_(std::make_unique<Impl>(src, kind, rate_hz, so, threads, noise_id_cap)) {}
Engine::~Engine() = default;
EngineResult Engine::run(const std::vector<EngineRequest>& req) { return impl_->run(req); }

Sums Engine::extra(Deviation type, std::size_t m) {
  Acc a = make_acc(type, m, impl_->spec.n);
  a.far = true;
  impl_->finish(a);
  Sums s;
  s.type = type;
  s.m = m;
  s.sum = a.sum;
  s.terms = a.terms;
  return s;
}

// One pass: the ring is sized, the accumulators classified (near / cursor / far) and grouped
// into work items; then either the whole record is built into memory and run without barriers,
// or it is streamed chunk by chunk; then the far accumulators and TOTDEV's edges.
EngineResult Engine::Impl::run(const std::vector<EngineRequest>& req) {
  EngineResult res;
  plan(req, res);
  if (ring_holds_all) run_in_memory();
  else run_streaming();

  // ---- far accumulators and TOTDEV edges: random access (ring or checkpoints) ----
  std::vector<std::size_t> post;
  for (std::size_t i = 0; i < accs.size(); ++i)
    if ((accs[i].far && accs[i].bases > 0) || (accs[i].type == Deviation::TOTDEV && accs[i].m > 1) ||
        lone_mdev_term(accs[i]))
      post.push_back(i);
  // The costliest first (points read: a far pass reads every window, TOTDEV's edges about 4m),
  // so that the last task to finish is a short one: in request order the largest tau's edges
  // (a tenth of all edge terms on log:100) ran last, on one core.
  const auto post_cost = [&](std::size_t i) {
    const Acc& a = accs[i];
    return (a.far ? a.bases * a.nwin : 0) + (a.type == Deviation::TOTDEV ? 4 * a.m : 0);
  };
  std::stable_sort(post.begin(), post.end(), [&](std::size_t x, std::size_t y) { return post_cost(x) > post_cost(y); });
  parallel_for(post.size(), threads, [&](std::size_t k) {
    poll();
    finish(accs[post[k]]);
  });
  for (Acc& a : accs)  // TOTDEV's shared interiors (every OADEV sum is final now)
    if (a.interior_of != Acc::kOwnInterior) {
      a.sum = accs[a.interior_of].sum + a.sum;
      a.terms += accs[a.interior_of].terms;
    }

  collect(res);
  return res;
}

void Engine::Impl::plan(const std::vector<EngineRequest>& req, EngineResult& res) {
  res.spec = spec;
  const std::uint64_t n = spec.n;
  phase_sums.reset(n);
  phase_last = 0;
  accs.clear();
  accs.reserve(req.size());
  for (const auto& r : req) accs.push_back(make_acc(r.type, r.m, n));
  for (Acc& t : accs) {
    if (t.type != Deviation::TOTDEV) continue;
    for (std::size_t j = 0; j < accs.size(); ++j)
      if (accs[j].type == Deviation::OADEV && accs[j].m == t.m) {
        t.interior_of = j;
        t.bases = 0;  // nothing of its own in the pass
        break;
      }
  }

  // Ring: the whole record when the budget holds it (then the noise-ID series are views of it,
  // collect()); else what the budget leaves after copies of those series. The next chunk is
  // built while the current one is processed: two chunks of slack.
  decim.clear();
  const std::size_t ring_need = static_cast<std::size_t>(n) + 2 * chunk;
  if (ring_need <= so.memory_budget_bytes / sizeof(double)) {
    ring.allocate(ring_need);
  } else {
    for (const auto& r : req) decim[r.m];  // one series per distinct m
    std::size_t decim_bytes = 0;
    for (auto& [m, v] : decim) {
      const std::size_t len = std::min<std::uint64_t>((n - 1) / m + 1, cap + 1);
      v.reserve(len);
      decim_bytes += len * sizeof(double);
    }
    const std::size_t floor_bytes = 8 * chunk * sizeof(double);
    const std::size_t budget = so.memory_budget_bytes > decim_bytes + floor_bytes
                                   ? so.memory_budget_bytes - decim_bytes
                                   : floor_bytes;
    ring.allocate(std::min(budget / sizeof(double), ring_need));
  }
  ring_holds_all = ring.size >= n;
  res.ring_points = ring.size;

  std::vector<std::size_t> near, cursors;
  for (std::size_t i = 0; i < accs.size(); ++i) {
    Acc& a = accs[i];
    // The windows (lags span, span - m, .. from the head) outside the ring: up to two are
    // rebuilt in-pass by cursors (one sequential rebuild each, instead of the random-access
    // path's rebuild of every window after the pass).
    auto in_ring = [&](std::size_t lag) { return lag + 2 * chunk <= ring.size; };
    std::size_t outside = 0;
    while (outside < a.nwin && !in_ring(a.span - outside * a.m)) ++outside;
    a.cursors = outside <= Acc::kMaxCursors && outside < a.nwin ? outside : 0;
    a.far = outside > 0 && a.cursors == 0;
    if (a.bases == 0) continue;
    if (a.far) ++res.far_count;
    else if (a.cursors) cursors.push_back(i);
    else near.push_back(i);
  }
  items = work_items(accs, near);
  for (std::size_t i : cursors) items.insert(items.begin(), std::vector<std::size_t>{i});  // the costliest items

  checkpoints.clear();
  checkpoints.reserve(n / kCheckpointEvery + 1);
  prev = {};
}

// P[lo, hi) into the ring, with the checkpoints and the noise-ID series (one thread at a time).
void Engine::Impl::produce(std::uint64_t lo, std::uint64_t hi) {
  for (std::uint64_t j = lo; j < hi;) {  // at most two pieces (the ring wraps)
    const std::size_t len = std::min<std::uint64_t>(hi - j, ring.room(j));
    check_source(j, len);
    builder.sequential(j, std::span<double>(ring.at(j), len), prev, scratch);
    phase_sums.add(j, ring.at(j), len);
    j += len;
  }
  if (hi == spec.n) phase_last = *ring.at(hi - 1);
  for (std::uint64_t j = (lo + kCheckpointEvery - 1) / kCheckpointEvery * kCheckpointEvery; j < hi;
       j += kCheckpointEvery)
    checkpoints.push_back(*ring.at(j));
  for (std::uint64_t j = lo; j < hi;) {  // contiguous pieces of the ring: no modulo per point
    const std::size_t len = std::min<std::uint64_t>(hi - j, ring.room(j));
    const double* piece = ring.at(j);
    for (auto& [m, v] : decim) {
      if (v.size() >= v.capacity()) continue;
      for (std::uint64_t x = (j + m - 1) / m * m; x < j + len && v.size() < v.capacity(); x += m)
        v.push_back(piece[x - j]);
    }
    j += len;
  }
}

// One work item over the heads [hi, hi2) (terms whose newest phase point is in that range).
void Engine::Impl::run_item(const std::vector<std::size_t>& item, std::vector<Acc>& a_set, std::uint64_t hi,
                            std::uint64_t hi2) {
  Acc& first = a_set[item[0]];
  if (first.cursors) {
    std::vector<double> sc;
    auto state_at = [&](std::uint64_t j) { return builder.state_at(j, checkpoints, sc); };
    auto prime = [&](Acc& a) {
      if (!a.modified()) return;
      mdev_prologue(a, [&](std::uint64_t lo, std::span<double> out) {
        PhaseState st = builder.state_at(lo, checkpoints, sc);
        builder.sequential(lo, out, st, sc);
      }, chunk);
    };
    return run_cursor(first, ring, builder, state_at, prime, hi, hi2);
  }
  if (item.size() >= 2 && (first.type == Deviation::OADEV || first.type == Deviation::TOTDEV ||
                            first.type == Deviation::OHDEV)) {
    Acc* chain[kMaxChain];
    for (std::size_t i = 0; i < item.size(); ++i) chain[i] = &a_set[item[i]];
    if (first.type == Deviation::OHDEV) return run_chain3(chain, static_cast<int>(item.size()), ring, hi, hi2);
    return run_chain(chain, static_cast<int>(item.size()), ring, hi, hi2);
  }
  for (std::size_t idx : item) {
    Acc& a = a_set[idx];
    const std::uint64_t lo_b = hi >= a.span ? hi - a.span : 0;
    const std::uint64_t hi_b = std::min<std::uint64_t>(hi2 >= a.span ? hi2 - a.span : 0, a.bases);
    if (lo_b >= hi_b) continue;
    if (a.modified() && !a.primed) {
      if (lo_b == 0) {  // the record's first term
        // P[0, 3m) is in the ring unwrapped (3m + 2 chunks fit it): read in place.
        mdev_prime_first(a, [&](std::size_t i, std::size_t) {
          return std::array<const double*, 3>{ring.at(i), ring.at(i + a.m), ring.at(i + 2 * a.m)};
        }, chunk);
      } else {  // a segment's first base (in memory: the whole record is in the ring)
        a.inner = sum_second_diff(ring.at(lo_b), ring.at(lo_b + a.m), ring.at(lo_b + 2 * a.m), a.m);
      }
      a.primed = true;
    }
    run_from_ring(a, ring, lo_b, hi_b);
  }
}

// In memory: build P whole, then no barriers at all. The heads are cut into a fixed number of
// segments (not per thread: the sums do not depend on the thread count); a segment runs every
// item chunk by chunk (the newest windows stay in L2 across items), and the partial sums are
// added in segment order. An MDEV/TDEV tau starts each segment from its window sum computed
// directly (O(m)); the few whose m makes that dearer than their share of the segment run whole.
void Engine::Impl::run_in_memory() {
  const std::uint64_t n = spec.n;
  build_in_memory();
  constexpr std::size_t kSegments = 32;
  auto keep_whole = [&](const std::vector<std::size_t>& item) {
    const Acc& a = accs[item[0]];
    // A segment's prime reads 3m cold points (about ten times the cost of the kernel's streamed
    // points, measured: 18 % of an MDEV run at a 19 % nominal bound); split only while the
    // primes are <= 1.2 % of the tau's points (~4n): 141 instead of 177 ms CPU for log:100 MDEV.
    return a.modified() && a.m * kSegments * 64 > n;
  };
  std::vector<std::size_t> whole, split;
  for (std::size_t k = 0; k < items.size(); ++k) (keep_whole(items[k]) ? whole : split).push_back(k);
  std::vector<std::vector<std::pair<double, std::size_t>>> part(kSegments);
  parallel_for(whole.size() + kSegments, threads, [&](std::size_t t) {
    if (t < whole.size()) {  // the costliest tasks first
      const std::vector<std::size_t>& item = items[whole[t]];
      for (std::uint64_t h = 0; h < n; h += chunk) {
        poll();
        run_item(item, accs, h, std::min<std::uint64_t>(n, h + chunk));
      }
      return;
    }
    const std::size_t g = t - whole.size();
    std::vector<Acc> local(accs.size());  // the split items' entries only
    for (std::size_t k : split)
      for (std::size_t idx : items[k]) {
        local[idx] = accs[idx];
        local[idx].sum = 0;
        local[idx].terms = 0;
      }
    const std::uint64_t h0 = n * g / kSegments, h1 = n * (g + 1) / kSegments;
    for (std::uint64_t h = h0; h < h1; h += chunk) {
      poll();
      for (std::size_t k : split) run_item(items[k], local, h, std::min(h1, h + chunk));
    }
    for (std::size_t k : split)
      for (std::size_t idx : items[k]) part[g].emplace_back(local[idx].sum, local[idx].terms);
  });
  for (std::size_t g = 0; g < kSegments; ++g) {
    std::size_t i = 0;
    for (std::size_t k : split)
      for (std::size_t idx : items[k]) {
        accs[idx].sum += part[g][i].first;
        accs[idx].terms += part[g][i].second;
        ++i;
      }
  }
}

// P whole into the ring, with the checkpoints. On two threads when the values are contiguous
// in memory: one builds [0, s); the other sums the blocks of [0, s) into the builder's state at
// s (phase_state_at: the same additions in the same order) and builds [s, n). Summing costs
// about a fifth of building (no stores, no fresh pages, no check; each part first faults in
// its own part of a mapped source, ChunkSource::will_read), so s = 0.55 n balances them (thread
// CPU 3.4 / 3.4 ms on 3.6e6 values; 3.7 / 3.2 ms at 0.6 n; 2.0 / 4.2 ms when the part that
// reads [0, s) first took all the file's page faults). The
// result is the sequential build's, bit for bit (Stream.OneThreadEqualsTwo and the
// stream/in-memory equalities check it).
void Engine::Impl::build_in_memory() {
  const std::uint64_t n = spec.n;
  auto build = [&](std::uint64_t lo, std::uint64_t hi, PhaseState st, std::vector<double>& sc) {
    for (std::uint64_t j = lo; j < hi; j += chunk) {
      if ((j - lo) % (64 * chunk) == 0) poll();
      const std::size_t len = static_cast<std::size_t>(std::min<std::uint64_t>(hi, j + chunk) - j);
      check_source(j, len);  // in cache now: the check costs no pass of its own
      builder.sequential(j, std::span<double>(ring.at(j), len), st, sc);
      phase_sums.add(j, ring.at(j), len);  // and so is the chunk just built
    }
  };
  const double* y = src.contiguous();
  constexpr std::uint64_t kSplitFrom = 1u << 20;  // below it a second thread costs more than it saves
  const std::uint64_t s = n * 11 / 20 / kCheckpointEvery * kCheckpointEvery;
  if (threads > 1 && y && n >= kSplitFrom && s > 0 && s < spec.n_src) {
    std::vector<double> sc0, sc1;
    // Each part stops at its first refused value; the lower part's refusal is the source's
    // first, so it is the one rethrown (parallel_for would rethrow whichever came first).
    std::exception_ptr err[2];
    parallel_for(2, 2, [&](std::size_t part) {
      try {
        if (part == 0) {
          src.will_read(0, s);  // each part faults in its own values' pages
          return build(0, s, PhaseState{}, sc0);
        }
        src.will_read(s, spec.n_src - s);
        build(s, n, spec.kind == DataKind::Frequency ? phase_state_at(y, s, spec.shift) : PhaseState{}, sc1);
      } catch (...) {
        err[part] = std::current_exception();
      }
    });
    for (const std::exception_ptr& e : err)
      if (e) std::rethrow_exception(e);
  } else {
    build(0, n, PhaseState{}, scratch);
  }
  for (std::uint64_t j = 0; j < n; j += kCheckpointEvery) checkpoints.push_back(*ring.at(j));
  phase_last = *ring.at(n - 1);
}

// Streaming: one barrier per chunk; building the next chunk is one more work item, so the read
// and the running sum overlap the kernels (the ring keeps two chunks of slack). The barrier's
// completion step (run once, by the last thread to arrive, before any is released) moves to
// the next chunk: one synchronisation per chunk instead of a "ready" and a "finished" one
// (11000 chunks in a 50-h record; each wait spins and yields, costly on a loaded machine).
void Engine::Impl::run_streaming() {
  const std::uint64_t n = spec.n;
  std::uint64_t hi = 0, hi2 = std::min<std::uint64_t>(n, chunk);
  std::atomic<std::size_t> next{0};
  bool done = false;
  // A read error (or a non-finite value) may surface on either thread: the first one is kept,
  // the chunk's remaining items are skipped, and it is rethrown here after the workers stop.
  std::exception_ptr err;
  std::mutex err_mutex;
  auto process_chunk = [&] {
    const std::size_t count = items.size() + 1;
    for (std::size_t k; (k = next.fetch_add(1)) < count;) try {
        poll();
        if (k == 0) {
          if (hi2 < n) produce(hi2, std::min<std::uint64_t>(n, hi2 + chunk));
          continue;
        }
        run_item(items[k - 1], accs, hi, hi2);
      } catch (...) {
        std::lock_guard lock(err_mutex);
        if (!err) err = std::current_exception();
        next = count;
      }
  };
  auto advance = [&]() noexcept {
    hi = hi2;
    if (hi >= n || err) {
      done = true;
      return;
    }
    hi2 = std::min<std::uint64_t>(n, hi + chunk);
    next = 0;
  };
  try {
    produce(0, hi2);
  } catch (...) {
    err = std::current_exception();
    done = true;
  }
  std::barrier sync(static_cast<std::ptrdiff_t>(threads), advance);
  auto loop = [&] {
    while (!done) {
      process_chunk();
      sync.arrive_and_wait();
    }
  };
  std::vector<std::jthread> workers;
  for (unsigned t = 1; t < threads && !done; ++t) workers.emplace_back(loop);
  loop();
  workers.clear();
  if (err) std::rethrow_exception(err);
}

// The sums and the noise-ID series, in the requests' order.
void Engine::Impl::collect(EngineResult& res) {
  const std::uint64_t n = spec.n;
  res.sums.resize(accs.size());
  for (std::size_t i = 0; i < accs.size(); ++i) {
    Sums& s = res.sums[i];
    s.type = accs[i].type;
    s.m = accs[i].m;
    s.sum = accs[i].sum;
    s.terms = accs[i].terms;
  }
  res.phase_sum = phase_sums.total();
  res.phase_last = phase_last;
  res.phase_abs_max = std::fabs(phase_last);
  for (const double c : checkpoints) res.phase_abs_max = std::max(res.phase_abs_max, std::fabs(c));
  res.decimated.clear();
  for (const Acc& a : accs) {
    if (res.decimated.count(a.m)) continue;
    const std::size_t all = static_cast<std::size_t>((n - 1) / a.m + 1);
    if (ring_holds_all) res.decimated.emplace(a.m, Decimated(ring.at(0), a.m, std::min(all, cap + 1)));
    else res.decimated.emplace(a.m, Decimated(std::move(decim[a.m])));
  }
  for (Sums& s : res.sums) s.decimated_complete = res.decimated.at(s.m).size() == (n - 1) / s.m + 1;
  decim.clear();
}

}  // namespace detail
}  // namespace rig::analysis
