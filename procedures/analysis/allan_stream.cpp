// The one-pass Allan-family engine (see allan_engine.hpp for the design).
#include <algorithm>
#include <atomic>
#include <barrier>
#include <bit>
#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <thread>

#include "procedures/analysis/allan_engine.hpp"

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

// ---------------------------------------------------------------------------------------------
// Kernels: sums of squared differences over contiguous windows w[k] = &P[base + k m].
// Compiled for AVX-512, AVX2 and baseline; the reductions are vectorised by `omp simd`.
#define RIG_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))

// Four independent vector accumulators: the sum is not one long FMA dependency chain.
using v8 = double __attribute__((vector_size(64)));
inline v8 load8(const double* p) {
  v8 v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline double hsum(v8 v) {
  double s = 0;
  for (int i = 0; i < 8; ++i) s += v[i];
  return s;
}

RIG_CLONES double sum_d2(const double* w0, const double* w1, const double* w2, std::size_t len) {
  v8 a0{}, a1{}, a2{}, a3{};
  std::size_t t = 0;
  for (; t + 32 <= len; t += 32) {
    const v8 d0 = load8(w2 + t) - 2 * load8(w1 + t) + load8(w0 + t);
    const v8 d1 = load8(w2 + t + 8) - 2 * load8(w1 + t + 8) + load8(w0 + t + 8);
    const v8 d2 = load8(w2 + t + 16) - 2 * load8(w1 + t + 16) + load8(w0 + t + 16);
    const v8 d3 = load8(w2 + t + 24) - 2 * load8(w1 + t + 24) + load8(w0 + t + 24);
    a0 += d0 * d0, a1 += d1 * d1, a2 += d2 * d2, a3 += d3 * d3;
  }
  double s = hsum((a0 + a1) + (a2 + a3));
  for (; t < len; ++t) {
    const double d = w2[t] - 2 * w1[t] + w0[t];
    s += d * d;
  }
  return s;
}

RIG_CLONES double sum_d3(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len) {
  v8 a0{}, a1{};
  std::size_t t = 0;
  for (; t + 16 <= len; t += 16) {
    const v8 d0 = load8(w3 + t) - 3 * load8(w2 + t) + 3 * load8(w1 + t) - load8(w0 + t);
    const v8 d1 = load8(w3 + t + 8) - 3 * load8(w2 + t + 8) + 3 * load8(w1 + t + 8) - load8(w0 + t + 8);
    a0 += d0 * d0, a1 += d1 * d1;
  }
  double s = hsum(a0 + a1);
  for (; t < len; ++t) {
    const double d = w3[t] - 3 * w2[t] + 3 * w1[t] - w0[t];
    s += d * d;
  }
  return s;
}

// MDEV: the m-window sum of second differences slides by one per base; its increment
// d[b+m] - d[b] is the third difference w3 - 3w2 + 3w1 - w0. The running sum is a prefix
// sum: done in tiles with four interleaved chains so it is not one long dependency chain.
RIG_CLONES void third_diff(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len,
                           double* out) {
#pragma omp simd
  for (std::size_t t = 0; t < len; ++t) out[t] = w3[t] - 3 * w2[t] + 3 * w1[t] - w0[t];
}

RIG_CLONES double sum_sq_offset(const double* v, std::size_t len, double off) {
  double s = 0;
#pragma omp simd reduction(+ : s)
  for (std::size_t t = 0; t < len; ++t) s += (v[t] + off) * (v[t] + off);
  return s;
}

double mdev_run(const double* w0, const double* w1, const double* w2, const double* w3, std::size_t len,
                double& inner) {
  constexpr std::size_t kTile = 1024, kQ = kTile / 4;
  double buf[kTile];
  double s = 0;
  for (std::size_t t0 = 0; t0 < len; t0 += kTile) {
    const std::size_t n = std::min(kTile, len - t0);
    third_diff(w0 + t0, w1 + t0, w2 + t0, w3 + t0, n, buf);
    if (n < kTile) {
      for (std::size_t t = 0; t < n; ++t) {
        inner += buf[t];
        s += inner * inner;
      }
      continue;
    }
    double c0 = 0, c1 = 0, c2 = 0, c3 = 0;  // local prefix sums of the four quarters
    for (std::size_t t = 0; t < kQ; ++t) {
      c0 += buf[t], buf[t] = c0;
      c1 += buf[kQ + t], buf[kQ + t] = c1;
      c2 += buf[2 * kQ + t], buf[2 * kQ + t] = c2;
      c3 += buf[3 * kQ + t], buf[3 * kQ + t] = c3;
    }
    s += sum_sq_offset(buf, kQ, inner);
    s += sum_sq_offset(buf + kQ, kQ, inner + c0);
    s += sum_sq_offset(buf + 2 * kQ, kQ, inner + c0 + c1);
    s += sum_sq_offset(buf + 3 * kQ, kQ, inner + c0 + c1 + c2);
    inner += c0 + c1 + c2 + c3;
  }
  return s;
}

// ---------------------------------------------------------------------------------------------
struct Acc {
  Deviation type{};
  std::size_t m = 0;
  std::size_t span = 0;   // highest phase offset of a term relative to its base
  std::size_t nwin = 0;   // windows (offsets 0, m, 2m[, 3m])
  std::size_t bases = 0;  // term bases 0..bases-1 (stride m for ADEV/HDEV)
  double sum = 0;
  std::size_t terms = 0;
  double inner = 0;       // MDEV state
  bool far = false;

  bool strided() const { return type == Deviation::ADEV || type == Deviation::HDEV; }
  bool modified() const { return type == Deviation::MDEV || type == Deviation::TDEV; }

  // Terms with base in [b0, b0 + len); w[k] = &P[b0 + k m], contiguous for len points.
  void run(std::size_t b0, std::size_t len, const double* const* w) {
    if (strided()) {
      std::size_t t = (b0 % m == 0) ? 0 : m - b0 % m;
      for (; t < len; t += m) {
        double d;
        if (nwin == 3) d = w[2][t] - 2 * w[1][t] + w[0][t];
        else d = w[3][t] - 3 * w[2][t] + 3 * w[1][t] - w[0][t];
        sum += d * d;
        ++terms;
      }
      return;
    }
    if (modified()) sum += mdev_run(w[0], w[1], w[2], w[3], len, inner);
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
// Builds P from the source, sequentially (main pass) or from a checkpoint (random access).
class PhaseBuilder {
 public:
  PhaseBuilder(const ChunkSource& src, PhaseSpec spec) : src_(src), spec_(spec) {}
  const PhaseSpec& spec() const { return spec_; }

  // Sequential: P[j] for j in [j0, j0 + out.size()), continuing from `prev` = P[j0 - 1].
  void sequential(std::uint64_t j0, std::span<double> out, double& prev, std::vector<double>& scratch) const {
    if (spec_.kind == DataKind::Phase) {
      pointwise(j0, out, scratch);
      return;
    }
    std::size_t k = 0;
    if (j0 == 0 && !out.empty()) {
      out[0] = 0;
      prev = 0;
      k = 1;
    }
    const std::size_t need = out.size() - k;
    if (need == 0) return;
    scratch.resize(need);
    fill(j0 + k - 1, scratch);  // y[j-1] for P[j]
    double p = prev;
    const double c = spec_.shift;
    for (std::size_t t = 0; t < need; ++t) {
      p = p + (scratch[t] - c);
      out[k + t] = p;
    }
    prev = p;
  }

  // Random access: P[lo, lo + out.size()) using the checkpoints (frequency data).
  void range(std::uint64_t lo, std::span<double> out, const std::vector<double>& checkpoints,
             std::vector<double>& scratch) const {
    if (spec_.kind == DataKind::Phase) {
      pointwise(lo, out, scratch);
      return;
    }
    const std::uint64_t cp = lo / kCheckpointEvery;
    double p = checkpoints.at(cp);
    std::uint64_t j = cp * kCheckpointEvery;
    if (j < lo) {  // advance from the checkpoint to lo, bit-identically to the main pass
      scratch.resize(lo - j);
      fill(j, scratch);
      for (double y : scratch) p = p + (y - spec_.shift);
      j = lo;
    }
    if (out.empty()) return;
    out[0] = p;
    if (out.size() > 1) {
      scratch.resize(out.size() - 1);
      fill(lo, scratch);
      for (std::size_t t = 1; t < out.size(); ++t) {
        p = p + (scratch[t - 1] - spec_.shift);
        out[t] = p;
      }
    }
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
  std::vector<double> buf;
  double* at(std::uint64_t j) { return buf.data() + (j % buf.size()); }
  std::size_t room(std::uint64_t j) const { return buf.size() - static_cast<std::size_t>(j % buf.size()); }
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

// MDEV's first term: the window sum of d[0..m-1] (P[0..3m-1]), from any random-access reader.
template <class ReadP>
void mdev_prologue(Acc& a, ReadP&& read, std::size_t block) {
  double inner = 0;
  std::vector<double> p0, p1, p2;
  for (std::size_t i = 0; i < a.m; i += block) {
    const std::size_t len = std::min(block, a.m - i);
    p0.resize(len), p1.resize(len), p2.resize(len);
    read(i, std::span<double>(p0));
    read(i + a.m, std::span<double>(p1));
    read(i + 2 * a.m, std::span<double>(p2));
    for (std::size_t t = 0; t < len; ++t) inner += p2[t] - 2 * p1[t] + p0[t];
  }
  a.inner = inner;
  a.sum += inner * inner;
  a.terms += 1;
}

// TOTDEV's reflected edge terms (NIST SP 1065 eq. 25: x*(1-j) = 2x(1) - x(1+j), x*(N+j) = 2x(N) - x(N-j)).
template <class ReadP>
void totdev_edges(Acc& a, std::uint64_t n, ReadP&& read, std::size_t block) {
  const std::size_t m = a.m;
  double first = 0, last = 0;
  read(0, std::span<double>(&first, 1));
  read(n - 1, std::span<double>(&last, 1));
  std::vector<double> r, c, f;
  // Left: i in [1, m-1]: 2P0 - P[m-i] - 2P[i] + P[i+m].
  for (std::size_t i = 1; i < m; i += block) {
    const std::size_t len = std::min(block, m - i);
    r.resize(len), c.resize(len), f.resize(len);
    read(m - i - (len - 1), std::span<double>(r));  // P[m-i-len+1 .. m-i], used reversed
    read(i, std::span<double>(c));
    read(i + m, std::span<double>(f));
    for (std::size_t t = 0; t < len; ++t) {
      const double d = 2 * first - r[len - 1 - t] - 2 * c[t] + f[t];
      a.sum += d * d;
    }
    a.terms += len;
  }
  // Right: i in [n-m, n-2]: P[i-m] - 2P[i] + 2P[n-1] - P[2(n-1) - i - m].
  const std::uint64_t i_lo = n - m, i_hi = n - 1;
  for (std::uint64_t i = i_lo; i < i_hi; i += block) {
    const std::size_t len = std::min<std::uint64_t>(block, i_hi - i);
    r.resize(len), c.resize(len), f.resize(len);
    read(i - m, std::span<double>(f));
    read(i, std::span<double>(c));
    // reflected indices 2(n-1) - (i+t) - m for t = 0..len-1: descending, lowest at t = len-1
    read(2 * (n - 1) - (i + len - 1) - m, std::span<double>(r));
    for (std::size_t t = 0; t < len; ++t) {
      const double d = f[t] - 2 * c[t] + 2 * last - r[len - 1 - t];
      a.sum += d * d;
    }
    a.terms += len;
  }
}

// Runs `fn(i)` for i in [0, count) over `threads` threads (dynamic assignment).
template <class Fn>
void parallel_for(std::size_t count, unsigned threads, Fn&& fn) {
  std::atomic<std::size_t> next{0};
  auto work = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < count;) fn(i);
  };
  std::vector<std::jthread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
}

}  // namespace

// Groups the accumulators of one chunk into work items for the cores. Same-type pairs m, 2m,
// 4m ... share windows (tau m reads P at b + m and b + 2m, tau 2m at b + 2m and b + 4m), so a
// doubling chain run in ascending order finds one of its two far windows still in L2: about
// half the memory traffic of independent taus. Chains are cut to <= 6 for load balance.
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
    for (std::size_t k = 0; k < chain.size(); k += 6)
      items.emplace_back(chain.begin() + static_cast<std::ptrdiff_t>(k),
                         chain.begin() + static_cast<std::ptrdiff_t>(std::min(chain.size(), k + 6)));
  }
  auto cost = [&](const std::vector<std::size_t>& it) {
    std::uint64_t c = 0;
    for (std::size_t i : it) c += (accs[i].modified() ? 2 : 1) * accs[i].bases;
    return c;
  };
  std::sort(items.begin(), items.end(), [&](const auto& a, const auto& b) { return cost(a) > cost(b); });
  return items;
}

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
  Ring ring;
  bool ring_holds_all = false;
  std::vector<double> checkpoints;

  auto reader(std::vector<double>& sc) {
    return [this, &sc](std::uint64_t lo, std::span<double> out) {
      if (ring_holds_all) {
        std::copy_n(ring.at(lo), out.size(), out.begin());
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
      const std::size_t len = std::min<std::uint64_t>(chunk, a.bases - b);
      for (std::size_t j = 0; j < a.nwin; ++j) {
        read(b + j * a.m, std::span<double>(win[j].data(), len));
        w[j] = win[j].data();
      }
      a.run(b, len, w);
    }
  }

  void finish(Acc& a) {
    std::vector<double> sc;
    if (a.far && a.bases > 0) {
      if (ring_holds_all) {
        if (a.modified()) mdev_prologue(a, reader(sc), chunk);
        const double* w[4];
        for (std::size_t j = 0; j < a.nwin; ++j) w[j] = ring.at(j * a.m);
        a.run(0, a.bases, w);
      } else {
        run_far(a);
      }
    }
    if (a.type == Deviation::TOTDEV && a.m > 1) totdev_edges(a, spec.n, reader(sc), chunk);
  }

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

EngineResult Engine::Impl::run(const std::vector<EngineRequest>& req) {
  EngineResult res;
  res.spec = spec;
  const std::uint64_t n = spec.n;

  std::vector<Acc> accs;
  accs.reserve(req.size());
  for (const auto& r : req) accs.push_back(make_acc(r.type, r.m, n));

  // Decimated series for noise identification, one per distinct m.
  std::map<std::size_t, std::vector<double>> decim;
  for (const auto& r : req) decim[r.m];
  std::size_t decim_bytes = 0;
  for (auto& [m, v] : decim) {
    const std::size_t len = std::min<std::uint64_t>((n - 1) / m + 1, cap + 1);
    v.reserve(len);
    decim_bytes += len * sizeof(double);
  }

  // Ring: what the budget leaves after the noise-ID series, never more than the record needs.
  const std::size_t floor_bytes = 8 * chunk * sizeof(double);
  const std::size_t budget = so.memory_budget_bytes > decim_bytes + floor_bytes ? so.memory_budget_bytes - decim_bytes
                                                                                : floor_bytes;
  const std::size_t ring_need = static_cast<std::size_t>(n) + chunk;
  ring.buf.assign(std::min(budget / sizeof(double), ring_need), 0.0);
  ring_holds_all = ring.buf.size() >= n;
  res.ring_points = ring.buf.size();

  std::vector<std::size_t> near;
  for (std::size_t i = 0; i < accs.size(); ++i) {
    Acc& a = accs[i];
    a.far = a.span + chunk > ring.buf.size();
    if (a.bases == 0) continue;
    if (a.far) ++res.far_count;
    else near.push_back(i);
  }
  const std::vector<std::vector<std::size_t>> items = work_items(accs, near);

  checkpoints.clear();
  checkpoints.reserve(n / kCheckpointEvery + 1);

  // ---- main pass ----
  std::vector<double> scratch;
  double prev = 0;
  std::uint64_t hi = 0, hi2 = 0;
  std::atomic<std::size_t> next{0};
  bool done = false;
  auto process_chunk = [&] {
    for (std::size_t k; (k = next.fetch_add(1)) < items.size();)
      for (std::size_t idx : items[k]) {
      Acc& a = accs[idx];
      const std::uint64_t lo_b = hi >= a.span ? hi - a.span : 0;
      const std::uint64_t hi_b = std::min<std::uint64_t>(hi2 >= a.span ? hi2 - a.span : 0, a.bases);
      if (lo_b >= hi_b) continue;
      if (a.modified() && a.terms == 0)
        mdev_prologue(a, [&](std::uint64_t j, std::span<double> out) {
          for (std::size_t t = 0; t < out.size(); ++t) out[t] = *ring.at(j + t);
        }, chunk);
      run_from_ring(a, ring, lo_b, hi_b);
      }
  };
  std::barrier sync(static_cast<std::ptrdiff_t>(threads));
  std::vector<std::jthread> workers;
  for (unsigned t = 1; t < threads; ++t)
    workers.emplace_back([&] {
      for (;;) {
        sync.arrive_and_wait();  // chunk ready (or done)
        if (done) return;
        process_chunk();
        sync.arrive_and_wait();  // chunk finished
      }
    });

  for (hi = 0; hi < n; hi = hi2) {
    hi2 = std::min<std::uint64_t>(n, hi + chunk);
    for (std::uint64_t j = hi; j < hi2;) {  // P[hi, hi2) into the ring (at most two pieces)
      const std::size_t len = std::min<std::uint64_t>(hi2 - j, ring.room(j));
      builder.sequential(j, std::span<double>(ring.at(j), len), prev, scratch);
      j += len;
    }
    for (std::uint64_t j = (hi + kCheckpointEvery - 1) / kCheckpointEvery * kCheckpointEvery; j < hi2;
         j += kCheckpointEvery)
      checkpoints.push_back(*ring.at(j));
    for (auto& [m, v] : decim) {
      if (v.size() >= v.capacity()) continue;
      for (std::uint64_t j = (hi + m - 1) / m * m; j < hi2 && v.size() < v.capacity(); j += m) v.push_back(*ring.at(j));
    }
    next = 0;
    if (threads > 1) sync.arrive_and_wait();
    process_chunk();
    if (threads > 1) sync.arrive_and_wait();
  }
  done = true;
  if (threads > 1) sync.arrive_and_wait();
  workers.clear();

  // ---- far accumulators and TOTDEV edges: random access (ring or checkpoints) ----
  std::vector<std::size_t> post;
  for (std::size_t i = 0; i < accs.size(); ++i)
    if ((accs[i].far && accs[i].bases > 0) || (accs[i].type == Deviation::TOTDEV && accs[i].m > 1)) post.push_back(i);
  parallel_for(post.size(), threads, [&](std::size_t k) { finish(accs[post[k]]); });

  res.sums.resize(accs.size());
  for (std::size_t i = 0; i < accs.size(); ++i) {
    Sums& s = res.sums[i];
    s.type = accs[i].type;
    s.m = accs[i].m;
    s.sum = accs[i].sum;
    s.terms = accs[i].terms;
    const auto& v = decim[accs[i].m];
    s.decimated = v;
    s.decimated_complete = v.size() == (n - 1) / accs[i].m + 1;
  }
  return res;
}

}  // namespace detail
}  // namespace rig::analysis
