// TOML helpers that turn every configuration mistake into a ConfigError naming
// the file, line and column (toml++ keeps source positions on every node).
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <toml++/toml.h>

#include "rig/core/errors.hpp"

namespace rig::cfg {

// Parses a file / a string; syntax errors become "file:line:col: message".
toml::table parse_file(const std::string& path);
toml::table parse_string(std::string_view text, const std::string& source_name);

// The folder a path written relative in `n`'s file resolves from: that file's own folder, or the
// one set_relative_folder gave its file (a run folder's copy of a profile resolves its paths where
// the profile was: run.json's profile_folder; a resume read `dbc = "x.dbc"` beside the copy, and
// every resume of such a run was exit 2: an integrator's review). Empty for a node in no file.
std::string relative_folder(const toml::node& n);
void set_relative_folder(const std::string& file, const std::string& folder);

// "file:line:col" of a node (or of its parent table when the key is missing); "command-line
// option" for one the program put there (from_option).
std::string where(const toml::node& n);

// Whether a node has no position in any file: put there by the program, a command-line option
// that overrides the file (rig table --unit, --drive; rig dut --can).
bool from_option(const toml::node& n);

// A value as the file writes it (arrays spelled out, a table as "a table", cut at 60
// characters), for errors of the form "file:line:col: 'key' = VALUE: must be ...".
std::string shown(const toml::node& n);

// Throws ConfigError "file:line:col: 'key' = VALUE: why" (where(n), shown(n)): a value of the
// right type that breaks a rule of its own (limits in order, a known base, ...).
[[noreturn]] void reject(const toml::node& n, std::string_view key, std::string_view why);

// Typed access. `required` throws when the key is missing; all throw when the
// value has the wrong type or lies outside [lo, hi].
double get_number(const toml::table& t, std::string_view key, std::optional<double> def = std::nullopt,
                  std::optional<double> lo = std::nullopt, std::optional<double> hi = std::nullopt);
int64_t get_int(const toml::table& t, std::string_view key, std::optional<int64_t> def = std::nullopt,
                std::optional<int64_t> lo = std::nullopt, std::optional<int64_t> hi = std::nullopt);
bool get_bool(const toml::table& t, std::string_view key, std::optional<bool> def = std::nullopt);
std::string get_string(const toml::table& t, std::string_view key,
                       std::optional<std::string> def = std::nullopt);
std::vector<double> get_numbers(const toml::table& t, std::string_view key,
                                std::optional<std::vector<double>> def = std::nullopt);
std::vector<std::string> get_strings(const toml::table& t, std::string_view key,
                                     std::optional<std::vector<std::string>> def = std::nullopt);
// A sub-table; nullptr when absent and not required.
const toml::table* get_table(const toml::table& t, std::string_view key, bool required = false);

// Rejects keys not in `allowed` (catches typos such as "run_sec").
void check_keys(const toml::table& t, std::initializer_list<std::string_view> allowed, std::string_view ctx);

// Prints "rig: warning: TEXT" on stderr once per process: a hardware file is read by several
// checks in one command, and a note about it is said once.
void warn_once(const std::string& text);

// Deep merge: values in `over` replace those in `base`; tables merge recursively.
// Copied nodes lose their source positions.
void merge_into(toml::table& base, const toml::table& over);
// Fills keys missing from `t` with `defaults`' (tables recursively). `t`'s own
// nodes keep their source positions, so errors still name the user's file.
void fill_defaults(toml::table& t, const toml::table& defaults);
// The same, taking `defaults`' nodes: they keep their source positions too, so an error in a
// value a file inherits names the place it came from (builtin:ci:15:1), not "command-line option".
void fill_defaults(toml::table& t, toml::table&& defaults);

}  // namespace rig::cfg
