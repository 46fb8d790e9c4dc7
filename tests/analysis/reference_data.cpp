#include "reference_data.hpp"

#include <zlib.h>

#include <sstream>
#include <stdexcept>

namespace rig::analysis::testing {

namespace {

std::string slurp(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");  // zlib reads plain files transparently
  if (!f) throw std::runtime_error("cannot open " + path);
  std::string out;
  char buf[1 << 16];
  int n;
  while ((n = gzread(f, buf, sizeof buf)) > 0) out.append(buf, static_cast<std::size_t>(n));
  gzclose(f);
  return out;
}

}  // namespace

std::string ref_path(const std::string& rel) { return std::string(RIG_ALLAN_REFERENCE_DIR) + "/" + rel; }

std::vector<double> read_values(const std::string& path) {
  std::istringstream in(slurp(path));
  std::vector<double> v;
  std::string line;
  while (std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    double x;
    if (ls >> x) v.push_back(x);
  }
  return v;
}

std::vector<S32Row> read_table(const std::string& path) {
  std::istringstream in(slurp(path));
  std::vector<S32Row> rows;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream ls(line);
    S32Row r;
    double tau;
    if (ls >> r.af >> tau >> r.terms >> r.alpha >> r.lo >> r.dev >> r.hi) rows.push_back(r);
  }
  if (rows.empty()) throw std::runtime_error("no rows in " + path);
  return rows;
}

}  // namespace rig::analysis::testing
