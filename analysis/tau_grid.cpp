// Tau grids and Stable32's stop ratios / term counts (tests/data/allan-reference/README.md).
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "analysis/allan.hpp"

namespace rig::analysis {

const char* to_string(Deviation d) {
  switch (d) {
    case Deviation::ADEV: return "adev";
    case Deviation::OADEV: return "oadev";
    case Deviation::MDEV: return "mdev";
    case Deviation::TDEV: return "tdev";
    case Deviation::HDEV: return "hdev";
    case Deviation::OHDEV: return "ohdev";
    case Deviation::TOTDEV: return "totdev";
  }
  return "?";
}

const char* to_string(DataKind k) { return k == DataKind::Frequency ? "freq" : "phase"; }

Deviation parse_deviation(const std::string& s) {
  for (Deviation d : {Deviation::ADEV, Deviation::OADEV, Deviation::MDEV, Deviation::TDEV, Deviation::HDEV,
                      Deviation::OHDEV, Deviation::TOTDEV})
    if (s == to_string(d)) return d;
  throw std::invalid_argument("unknown deviation '" + s + "' (adev|oadev|mdev|tdev|hdev|ohdev|totdev)");
}

DataKind parse_data_kind(const std::string& s) {
  if (s == "freq" || s == "frequency") return DataKind::Frequency;
  if (s == "phase") return DataKind::Phase;
  throw std::invalid_argument("unknown data kind '" + s + "' (freq|phase)");
}

TauGrid parse_tau_grid(const std::string& s) {
  TauGrid g;
  if (s == "octave") g.kind = TauGrid::Octave;
  else if (s == "decade") g.kind = TauGrid::Decade;
  else if (s == "all") g.kind = TauGrid::All;
  else if (s.rfind("log:", 0) == 0) {
    g.kind = TauGrid::Log;
    const std::string num = s.substr(4);
    // Decimal digits only, no sign and no leading zero, as every whole number the rig reads (stoi
    // took "log:+5" and "log:010", which m:LIST refuses: a review).
    const bool digits = !num.empty() && num.size() <= 6 && num[0] != '0' &&
                        num.find_first_not_of("0123456789") == std::string::npos;
    const int n = digits ? std::stoi(num) : 0;
    if (!digits || n < 2 || n > 100000)
      throw std::invalid_argument("tau grid '" + s +
                                  "': log:N needs a whole number N in 2..100000 (decimal digits, no sign or leading zero)");
    g.log_n = n;
  } else {
    throw std::invalid_argument("unknown tau grid '" + s + "' (octave|decade|all|log:N)");
  }
  return g;
}

std::size_t max_factor(Deviation d, std::size_t n_phase) {
  if (n_phase < 2) return 0;
  const std::size_t n1 = n_phase - 1;
  switch (d) {
    case Deviation::ADEV:
    case Deviation::HDEV: return n1 / 5;
    case Deviation::OADEV:
    case Deviation::MDEV:
    case Deviation::TDEV:
    case Deviation::OHDEV: return n1 / 4;
    case Deviation::TOTDEV: return n1 / 2;
  }
  return 0;
}

std::vector<std::size_t> tau_factors(const TauGrid& g, Deviation d, std::size_t n_phase) {
  const std::size_t top = max_factor(d, n_phase);
  std::vector<std::size_t> m;
  if (top < 1) return m;
  switch (g.kind) {
    case TauGrid::Octave:
      for (std::size_t v = 1; v <= top; v *= 2) m.push_back(v);
      break;
    case TauGrid::Decade:
      for (std::size_t dec = 1; dec <= top; dec *= 10)
        for (std::size_t k : {1u, 2u, 4u})
          if (k * dec <= top) m.push_back(k * dec);
      break;
    case TauGrid::All:
      for (std::size_t v = 1; v <= top; ++v) m.push_back(v);
      break;
    case TauGrid::Log: {
      // q points per octave so that about log_n points span [1, top].
      const double octaves = std::max(1.0, std::log2(static_cast<double>(top)));
      const int q = std::max(1, static_cast<int>(std::ceil((g.log_n - 1) / octaves)));
      constexpr std::size_t kSeed = 64;
      std::vector<std::size_t> v;
      for (int k = 0;; ++k) {  // below the seed octave: rounded log spacing
        const auto r = static_cast<std::size_t>(std::llround(std::exp2(static_cast<double>(k) / q)));
        if (r >= kSeed || r > top) break;
        v.push_back(r);
      }
      for (int j = 0; j < q; ++j) {  // seeds and their doublings
        const auto seed = static_cast<std::size_t>(std::llround(kSeed * std::exp2(static_cast<double>(j) / q)));
        for (std::size_t x = seed; x <= top; x *= 2) v.push_back(x);
      }
      std::sort(v.begin(), v.end());
      v.erase(std::unique(v.begin(), v.end()), v.end());
      while (!v.empty() && v.back() > top) v.pop_back();
      m = v;
      break;
    }
  }
  return m;
}

std::size_t term_count(Deviation d, std::size_t n, std::size_t m) {
  if (m == 0) return 0;
  auto sub = [](std::size_t a, std::size_t b) { return a > b ? a - b : 0; };
  switch (d) {
    case Deviation::ADEV: return sub((n - 1) / m, 1);
    case Deviation::OADEV: return sub(n, 2 * m);
    case Deviation::MDEV:
    case Deviation::TDEV: return sub(n + 1, 3 * m);
    case Deviation::HDEV: return sub((n - 1) / m, 2);
    case Deviation::OHDEV: return sub(n, 3 * m);
    case Deviation::TOTDEV: return sub(n, 2);
  }
  return 0;
}

}  // namespace rig::analysis
