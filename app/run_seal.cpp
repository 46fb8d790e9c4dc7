#include "app/run_seal.hpp"

#include <algorithm>
#include <filesystem>

#include "rig/core/errors.hpp"
#include "rig/executive/executive.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

std::optional<seal::Key> station_key(const std::string& option) {
  if (option.empty()) return std::nullopt;
  return seal::load_key(option);
}

std::vector<std::string> sealable_files(const std::string& dir) {
  std::vector<std::string> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    const std::string rel = it->path().lexically_relative(dir).generic_string();
    if (it->is_symlink())
      throw ConfigError(dir + "/" + rel + ": a symbolic link in a sealed run folder (a sealed folder holds its own "
                                          "files; what a link points at could change without the seal)");
    if (name.rfind('.', 0) == 0) {
      if (it->is_directory()) it.disable_recursion_pending();
      continue;
    }
    if (!it->is_regular_file()) continue;
    if (rel == "run.log" || rel == "seal.json" || rel == "seal.prev.json" ||
        (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) ||
        name.find(".interrupted-") != std::string::npos)
      continue;
    files.push_back(rel);
  }
  std::sort(files.begin(), files.end());
  return files;
}

void seal_run_folder(const std::string& dir, const seal::Key& k, const std::optional<std::string>& checkpoint_text) {
  std::vector<seal::Entry> entries;
  for (const std::string& rel : sealable_files(dir))
    if (!checkpoint_text || rel != "checkpoint.json") entries.push_back({rel, "", false});
  if (checkpoint_text) entries.push_back({"checkpoint.json", *checkpoint_text, true});
  const std::string text = seal::make_seal(dir, k, entries);
  try {
    if (fs::exists(dir + "/seal.json")) fs::rename(dir + "/seal.json", dir + "/seal.prev.json");
    write_file_atomic(dir + "/seal.json", text);
  } catch (const std::exception& e) {
    throw ConfigError(dir + "/seal.json: cannot be written: " + e.what());
  }
}

void drop_previous_seal(const std::string& dir) {
  std::error_code ec;
  fs::remove(dir + "/seal.prev.json", ec);
}

bool rewritten_by_a_resume(const std::string& rel) {
  return rel == "passport.json" || rel == "junit.xml" || rel == "analysis.json" || rel == "report.html" ||
         rel == "loop-test.csv";
}

namespace {

// A seal holds for a resume when it is this key's, its list is whole, it covers what a resume
// reads, and every file it lists that a resume reads is as sealed.
bool holds_for_resume(const seal::Check& c, std::string& why) {
  std::vector<std::string> bad;
  for (const std::string& p : c.problems) {
    const std::string rel = p.substr(0, p.find(':'));
    const bool output = std::any_of(c.files.begin(), c.files.end(), [&](const auto& f) { return f.first == rel; }) &&
                        rewritten_by_a_resume(rel);
    if (!output) bad.push_back(p);
  }
  for (const std::string& p : bad) why += (why.empty() ? "" : "; ") + p;
  return bad.empty();
}

}  // namespace

std::vector<std::string> check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k) {
  const bool sealed = fs::exists(dir + "/seal.json") || fs::exists(dir + "/seal.prev.json");
  if (!k) {
    if (sealed)
      throw ConfigError(dir + " is sealed (seal.json): resume it with the station's key (--seal-key FILE or "
                              "RIG_SEAL_KEY); without it the resumed run could not be sealed");
    return {};
  }
  if (!sealed)
    throw ConfigError(dir + " is not sealed (no seal.json): the key cannot vouch for files it never sealed; resume "
                            "it without --seal-key (it stays unsealed) or start a new run");
  std::vector<std::string> must = {"run.json", "profile.toml"};
  if (fs::exists(Executive::checkpoint_path(dir))) must.push_back("checkpoint.json");
  std::string why;
  for (const char* name : {"seal.json", "seal.prev.json"}) {
    const std::string path = dir + "/" + name;
    if (!fs::exists(path) && !fs::is_symlink(path)) continue;
    const seal::Check c = seal::check_seal(dir, path, *k, must);
    std::string w;
    if (holds_for_resume(c, w)) {
      std::vector<std::string> files;
      for (const auto& f : c.files) files.push_back(f.first);
      return files;
    }
    why += (why.empty() ? "" : "; ") + std::string(name) + ": " + w;
  }
  const bool other_key = why.find("sealed with another key") != std::string::npos;
  throw ConfigError(dir + ": the station's seal does not hold (" + why + "): " +
                    (other_key ? "resume with the key it was sealed with"
                               : "the folder was changed outside the rig; start a new run"));
}

void refuse_added_files(const std::string& dir, const std::vector<std::string>& sealed,
                        const std::string& next_phase) {
  // The recording of phase "raw" is captures/raw-U10.cap: its capture starts with the phase id.
  const std::string partial = "captures/" + next_phase;
  auto left_partial = [&](const std::string& f) {
    return !next_phase.empty() && f.rfind(partial, 0) == 0 && f.size() > 4 && f.compare(f.size() - 4, 4, ".cap") == 0;
  };
  for (const std::string& f : sealable_files(dir))
    if (std::find(sealed.begin(), sealed.end(), f) == sealed.end() && !left_partial(f) && !rewritten_by_a_resume(f))
      throw ConfigError(dir + "/" + f + ": not sealed (added after the seal): the folder was changed outside the rig; "
                                        "start a new run");
}

}  // namespace rig::cli
