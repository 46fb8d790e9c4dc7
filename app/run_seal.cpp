#include "app/run_seal.hpp"

#include <filesystem>

#include "rig/core/errors.hpp"
#include "rig/executive/executive.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

std::optional<seal::Key> station_key(const std::string& option) {
  if (option.empty()) return std::nullopt;
  return seal::load_key(option);
}

namespace {

std::vector<std::string> run_folder_files(const std::string& dir) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() && name.rfind('.', 0) == 0) {
      it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file()) continue;
    const std::string rel = fs::relative(it->path(), dir).generic_string();
    if (rel == "run.log" || rel == "seal.json" || rel == "seal.prev.json" || name.rfind('.', 0) == 0 ||
        (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0))
      continue;
    files.push_back(rel);
  }
  return files;
}

}  // namespace

void seal_run_folder(const std::string& dir, const seal::Key& k, const std::optional<std::string>& checkpoint_text) {
  std::vector<seal::Entry> entries;
  for (const std::string& rel : run_folder_files(dir))
    if (!checkpoint_text || rel != "checkpoint.json") entries.push_back({rel, "", false});
  if (checkpoint_text) entries.push_back({"checkpoint.json", *checkpoint_text, true});
  const std::string text = seal::make_seal(dir, k, entries);
  std::error_code ec;
  if (fs::exists(dir + "/seal.json")) fs::rename(dir + "/seal.json", dir + "/seal.prev.json", ec);
  if (ec) throw std::runtime_error(dir + "/seal.json: cannot be kept as seal.prev.json: " + ec.message());
  write_file_atomic(dir + "/seal.json", text);
}

void drop_previous_seal(const std::string& dir) {
  std::error_code ec;
  fs::remove(dir + "/seal.prev.json", ec);
}

void check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k) {
  const bool sealed = fs::exists(dir + "/seal.json") || fs::exists(dir + "/seal.prev.json");
  if (!k) {
    if (sealed)
      throw ConfigError(dir + " is sealed (seal.json): resume it with the station's key (--seal-key FILE or RIG_SEAL_KEY); without it the resumed run could not be sealed");
    return;
  }
  std::vector<std::string> must = {"run.json", "profile.toml"};
  if (fs::exists(Executive::checkpoint_path(dir))) must.push_back("checkpoint.json");
  const seal::Check now = seal::check_seal(dir, dir + "/seal.json", *k, must);
  if (now.ok) return;
  if (fs::exists(dir + "/seal.prev.json") && seal::check_seal(dir, dir + "/seal.prev.json", *k, must).ok) return;
  std::string what;
  bool other_key = false;
  for (const std::string& p : now.problems) {
    what += (what.empty() ? "" : "; ") + p;
    other_key = other_key || p.find("sealed with another key") != std::string::npos;
  }
  throw ConfigError(dir + ": the station's seal does not hold (" + what + "): " +
                    (other_key ? "resume with the key it was sealed with"
                               : "the folder was changed outside the rig; start a new run"));
}

}  // namespace rig::cli
