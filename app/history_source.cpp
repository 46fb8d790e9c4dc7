#include "app/history_source.hpp"

#include <filesystem>
#include <optional>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/toml_util.hpp"
#include "rig/report/db_url.hpp"
#include "rig/report/history.hpp"

namespace rig::cli {

namespace {

namespace fs = std::filesystem;

// The rig config holds [history] only. A mistyped section ([histori]) was skipped without a
// word, and the runs recorded into the default database (a review): refused as the hardware
// file refuses one. The keys of [history] are default_db_url's to check; its url is checked
// here, at its line (it was named later without one).
void check_rig_config(const std::string& path) {
  const toml::table t = cfg::parse_file(path);
  for (auto&& [k, v] : t)
    if (k.str() != "history")
      throw ConfigError(cfg::where(v) + ": unknown section '" + shown_text(k.str()) +
                        "' in the rig config (expected: history; docs/history.md)");
  const toml::table* h = cfg::get_table(t, "history");
  const toml::node* url = h ? h->get("url") : nullptr;
  if (url && url->is_string())
    if (const std::string why = history::url_problem(*url->value<std::string>()); !why.empty())
      throw ConfigError(cfg::where(*url) + ": 'url' = '" + shown_text(history::mask_password(*url->value<std::string>())) +
                        "': " + why);
}

}  // namespace

HistorySource default_history() {
  if (const std::optional<std::string> e = history::history_from_environment()) {
    const std::string& url = *e;
    try {
      (void)history::sqlite_path(url);  // a URL rig cannot open: another scheme, no file
    } catch (const ConfigError& bad) {
      throw ConfigError(std::string("RIG_HISTORY: ") + bad.what());
    }
    return {url, true};
  }
  if (const std::optional<std::string> config = history::rig_config_path()) check_rig_config(*config);
  return {history::default_db_url(), false};
}

}  // namespace rig::cli
