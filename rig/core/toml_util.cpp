#include "rig/core/toml_util.hpp"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>

#include "rig/core/escape.hpp"
#include "rig/core/number_text.hpp"

namespace rig::cfg {

namespace {

bool no_position(const toml::source_region& s) { return !s.path && s.begin.line == 0; }

std::string pos(const toml::source_region& s) {
  if (no_position(s)) return "command-line option";  // (from_option)
  std::ostringstream os;
  // The path as typed (--profile, --hardware) with its control bytes as \xNN: not sent to the terminal.
  os << (s.path ? shown_text(*s.path) : std::string("<config>")) << ':' << s.begin.line << ':' << s.begin.column;
  return os.str();
}

[[noreturn]] void fail(const toml::node& n, const std::string& msg) { throw ConfigError(where(n) + ": " + msg); }

[[noreturn]] void wrong_type(const toml::node& n, std::string_view key, std::string_view want) {
  reject(n, key, "must be " + std::string(want));
}

const toml::node& need(const toml::table& t, std::string_view key) {
  const toml::node* n = t.get(key);
  if (!n) fail(t, "missing key '" + std::string(key) + "'");
  return *n;
}

// A value or a bound as text: a whole number as one (`retries = 1000000000` was "1e+09", a
// review), any other as its shortest text (toml++ wrote 'tolerance_deg' = 1.0000000000000001e-05
// for 0.00001, and the stream's six digits read 'run_s' = 0.00199999999 as '0.002 is out of range
// [0.002, ...]'; reviews).
std::string number_text(double v) {
  if (std::isfinite(v) && v == std::trunc(v) && std::fabs(v) < 9.007199254740992e15) return std::to_string(static_cast<int64_t>(v));
  return shortest_text(v);
}

void check_range(const toml::node& n, std::string_view key, double v, const std::string& shown_v,
                 std::optional<double> lo, std::optional<double> hi) {
  if (!std::isfinite(v) || (lo && v < *lo) || (hi && v > *hi)) {
    std::ostringstream os;
    os << "'" << key << "' = " << shown_v;
    if (lo || hi) {
      os << " is out of range [" << (lo ? number_text(*lo) : "-inf") << ", " << (hi ? number_text(*hi) : "inf") << "]";
    } else {
      os << ": not a finite number";
    }
    fail(n, os.str());
  }
}

// The token a value was written as, from its line and column in `text` (toml++ counts columns in
// code points; a line may hold UTF-8 before the value).
std::string_view token_at(std::string_view text, const toml::source_position& at) {
  std::size_t i = 0;
  for (uint32_t line = 1; line < at.line && i < text.size(); ++line) {
    const std::size_t nl = text.find('\n', i);
    if (nl == std::string_view::npos) return {};
    i = nl + 1;
  }
  for (uint32_t col = 1; col < at.column && i < text.size() && text[i] != '\n'; ++col) {
    ++i;
    while (i < text.size() && (static_cast<unsigned char>(text[i]) & 0xC0) == 0x80) ++i;  // continuation bytes
  }
  const std::size_t end = text.find_first_of(" \t\r\n,]}#", i);
  return text.substr(i, end == std::string_view::npos ? std::string_view::npos : end - i);
}

// A float written non-zero that toml++ read as 0 (nearer 0 than the smallest double: 1e-400) is
// refused at its place: a limit `[0, 1e-400]` became [0, 0] without a word (a review).
void refuse_underflow(const toml::node& n, std::string_view text) {
  if (const auto* a = n.as_array()) {
    for (const toml::node& e : *a) refuse_underflow(e, text);
  } else if (const auto* t = n.as_table()) {
    for (const auto& [k, v] : *t) refuse_underflow(v, text);
  } else if (const auto* f = n.as_floating_point(); f && f->get() == 0.0) {
    const std::string_view tok = token_at(text, n.source().begin);
    const std::string_view mantissa = tok.substr(0, tok.find_first_of("eE"));
    if (mantissa.find_first_of("123456789") != std::string_view::npos)
      fail(n, std::string(tok) + " is nearer 0 than the smallest double (about 4.9e-324): write 0, or a value a double holds");
  }
}

toml::table parsed(std::string_view text, const std::string& source_name) {
  try {
    toml::table t = toml::parse(text, source_name);
    refuse_underflow(t, text);
    return t;
  } catch (const toml::parse_error& e) {
    std::ostringstream os;
    os << pos(e.source()) << ": " << e.description();
    throw ConfigError(os.str());
  }
}

}  // namespace

namespace {
std::mutex folders_mu;
std::map<std::string, std::string>& relative_folders() {
  static std::map<std::string, std::string> m;
  return m;
}
}  // namespace

void set_relative_folder(const std::string& file, const std::string& folder) {
  std::lock_guard lk(folders_mu);
  relative_folders()[file] = folder;
}

std::string relative_folder(const toml::node& n) {
  const auto& src = n.source().path;
  if (!src) return "";
  std::lock_guard lk(folders_mu);
  if (const auto it = relative_folders().find(*src); it != relative_folders().end()) return it->second;
  return std::filesystem::path(*src).parent_path().string();
}

std::string where(const toml::node& n) { return pos(n.source()); }

bool from_option(const toml::node& n) { return no_position(n.source()); }

std::string shown(const toml::node& n) {
  if (n.is_table()) return "a table";
  // A float as its shortest text, kept a TOML float (300.0); an array element by element.
  if (const auto* f = n.as_floating_point(); f && std::isfinite(f->get())) {
    std::string s = shortest_text(f->get());
    if (s.find_first_of(".e") == std::string::npos) s += ".0";
    return s;
  }
  if (const auto* a = n.as_array()) {
    std::string s = "[";
    for (std::size_t i = 0; i < a->size(); ++i) s += (i ? ", " : " ") + shown(*a->get(i));
    s += a->empty() ? "]" : " ]";
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
  }
  std::ostringstream os;
  n.visit([&](const auto& v) { os << v; });
  std::string s = os.str();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

void warn_once(const std::string& text) {
  static std::mutex mu;
  static std::set<std::string> said;
  std::lock_guard lk(mu);
  if (said.insert(text).second) std::cerr << "rig: warning: " << text << "\n" << std::flush;
}

void reject(const toml::node& n, std::string_view key, std::string_view why) {
  fail(n, "'" + std::string(key) + "' = " + shown(n) + ": " + std::string(why));
}

toml::table parse_file(const std::string& path) {
  // toml++ says "FILE:0:0: File could not be opened for reading" for a file that is not there.
  std::error_code ec;
  if (!std::filesystem::exists(path, ec))
    throw ConfigError(shown_text(path) + (ec ? ": cannot be read: " + ec.message() : std::string(": no such file")));
  if (std::filesystem::is_directory(path, ec)) throw ConfigError(shown_text(path) + ": a folder, not a file");
  // A FIFO's open waits for a writer that may never come, with every signal the watcher takes
  // lost on the blocked main thread (a review: `--profile FIFO` ended only by SIGKILL); a device
  // reads as whatever it yields (/dev/zero as an empty file). Only a regular file is read.
  if (!std::filesystem::is_regular_file(path, ec))
    throw ConfigError(shown_text(path) + ": not a regular file (a pipe, a device or a socket): give the file itself");
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  if (in) text << in.rdbuf();
  if (!in || in.bad())  // toml++ said "FILE:0:0: File could not be opened for reading", with no reason
    throw ConfigError(shown_text(path) + ": cannot be read: " + std::strerror(errno));
  return parsed(text.str(), path);
}

toml::table parse_string(std::string_view text, const std::string& source_name) { return parsed(text, source_name); }

double get_number(const toml::table& t, std::string_view key, std::optional<double> def, std::optional<double> lo,
                  std::optional<double> hi) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  std::optional<double> v = n->value<double>();  // integers convert too
  if (!v || !(n->is_floating_point() || n->is_integer())) wrong_type(*n, key, "a number");
  check_range(*n, key, *v, shortest_text(*v), lo, hi);
  return *v;
}

int64_t get_int(const toml::table& t, std::string_view key, std::optional<int64_t> def, std::optional<int64_t> lo,
                std::optional<int64_t> hi) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  if (!n->is_integer()) wrong_type(*n, key, "an integer");
  const int64_t v = *n->value<int64_t>();
  check_range(*n, key, static_cast<double>(v), std::to_string(v),
              lo ? std::optional<double>(static_cast<double>(*lo)) : std::nullopt,
              hi ? std::optional<double>(static_cast<double>(*hi)) : std::nullopt);
  return v;
}

bool get_bool(const toml::table& t, std::string_view key, std::optional<bool> def) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  if (!n->is_boolean()) wrong_type(*n, key, "true or false");
  return *n->value<bool>();
}

std::string get_string(const toml::table& t, std::string_view key, std::optional<std::string> def) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  if (!n->is_string()) wrong_type(*n, key, "a string");
  return *n->value<std::string>();
}

std::vector<double> get_numbers(const toml::table& t, std::string_view key, std::optional<std::vector<double>> def) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  const toml::array* a = n->as_array();
  if (!a) wrong_type(*n, key, "an array of numbers");
  std::vector<double> out;
  for (const toml::node& e : *a) {
    std::optional<double> v = e.value<double>();
    if (!v || !(e.is_floating_point() || e.is_integer())) wrong_type(e, key, "an array of numbers");
    check_range(e, key, *v, shortest_text(*v), std::nullopt, std::nullopt);
    out.push_back(*v);
  }
  return out;
}

std::vector<std::string> get_strings(const toml::table& t, std::string_view key,
                                     std::optional<std::vector<std::string>> def) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (def) return *def;
    need(t, key);
  }
  const toml::array* a = n->as_array();
  if (!a) wrong_type(*n, key, "an array of strings");
  std::vector<std::string> out;
  for (const toml::node& e : *a) {
    if (!e.is_string()) wrong_type(e, key, "an array of strings");
    out.push_back(*e.value<std::string>());
  }
  return out;
}

const toml::table* get_table(const toml::table& t, std::string_view key, bool required) {
  const toml::node* n = t.get(key);
  if (!n) {
    if (required) need(t, key);
    return nullptr;
  }
  if (!n->is_table()) wrong_type(*n, key, "a table");
  return n->as_table();
}

void check_keys(const toml::table& t, std::initializer_list<std::string_view> allowed, std::string_view ctx) {
  for (auto&& [k, v] : t) {
    bool ok = false;
    for (auto a : allowed) ok = ok || a == k.str();
    if (!ok) {
      std::string list;
      for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      // At the key as typed, not at its value (`rn_s = 2.0` was named at column 8: a review).
      const toml::source_region& at = no_position(k.source()) ? v.source() : k.source();
      throw ConfigError(pos(at) + ": unknown key '" + std::string(k.str()) + "' in [" + std::string(ctx) +
                        "] (expected one of: " + list + ")");
    }
  }
}

void fill_defaults(toml::table& t, const toml::table& defaults) {
  for (auto&& [k, v] : defaults) {
    toml::node* mine = t.get(k.str());
    if (!mine) {
      t.insert(k, v);
    } else if (mine->is_table() && v.is_table()) {
      fill_defaults(*mine->as_table(), *v.as_table());
    }
  }
}

void fill_defaults(toml::table& t, toml::table&& defaults) {
  for (auto&& [k, v] : defaults) {
    toml::node* mine = t.get(k.str());
    if (!mine) {
      t.insert(k, std::move(v));  // moved, a node keeps its source (a copy has none: toml++ issue 49)
    } else if (mine->is_table() && v.is_table()) {
      fill_defaults(*mine->as_table(), std::move(*v.as_table()));
    }
  }
}

void merge_into(toml::table& base, const toml::table& over) {
  for (auto&& [k, v] : over) {
    toml::node* b = base.get(k.str());
    if (b && b->is_table() && v.is_table()) {
      merge_into(*b->as_table(), *v.as_table());
    } else {
      base.insert_or_assign(k, v);
    }
  }
}

}  // namespace rig::cfg
