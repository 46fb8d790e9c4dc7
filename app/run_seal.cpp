#include "app/run_seal.hpp"
#include "rig/core/json_unique.hpp"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>

#include <sys/stat.h>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <nlohmann/json.hpp>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/file_stamp.hpp"
#include "rig/executive/executive.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

std::optional<seal::Key> station_key(const std::string& option, bool given) {
  const char* env = std::getenv("RIG_SEAL_KEY");
  if ((given || env) && option.empty())
    throw ConfigError("--seal-key / RIG_SEAL_KEY: empty; name the station's key (or unset RIG_SEAL_KEY)");
  if (option.empty()) return std::nullopt;
  return seal::load_key(option);
}

namespace {

// The MAC this process took of a record, and which file it took it of (rig/core/file_stamp.hpp).
struct CarriedMac {
  std::uint64_t inode = 0, device = 0;
  std::string mac;
  std::string key_id;
};

// A record (its invocation, profile, captures, the loop test's records) is written once, so the
// MAC this process first took of it, at the checkpoint after its writer closed it, is carried to
// every later seal while the name holds the same file: read again each time, a record edited in
// place between two seals with its size and modification time kept (which the run's stamps
// cannot see) was vouched for as edited (a review). A record written again (a resume re-records a
// phase: its earlier file set aside, a new one created) is another file, read again. Kept in
// this process only: a resume starts from the seal it checked, and reads every file once more.
std::map<std::string, CarriedMac>& carried_macs() {
  static std::map<std::string, CarriedMac> carried;
  return carried;
}

}  // namespace

void seal_run_folder(const std::string& dir, const seal::Key& k, const std::vector<std::string>& files,
                     const std::optional<std::string>& checkpoint_text, const std::string& outcome) {
  std::vector<seal::Entry> entries;
  std::vector<std::pair<std::string, CarriedMac>> taken;  // carried once this seal is written
  for (const std::string& rel : files) {
    if (checkpoint_text && rel == "checkpoint.json") continue;
    seal::Entry e{rel, "", false, ""};
    if (is_record(rel)) {
      const std::string path = fs::absolute(dir + "/" + rel).lexically_normal().string();
      if (const std::optional<FileStamp> now = stamp_of(path)) {
        const auto was = carried_macs().find(path);
        if (was != carried_macs().end() && was->second.inode == now->inode && was->second.device == now->device &&
            was->second.key_id == k.id) {
          e.mac = was->second.mac;
        } else {
          try {
            e.mac = seal::file_mac(k, path);
            taken.emplace_back(path, CarriedMac{now->inode, now->device, e.mac, k.id});
          } catch (const std::exception&) {  // make_seal reads it and says why
            e.mac.clear();
          }
        }
      }
    }
    entries.push_back(std::move(e));
  }
  if (checkpoint_text) entries.push_back({"checkpoint.json", *checkpoint_text, true, ""});
  try {
    const std::string text = seal::make_seal(dir, k, entries, outcome);
    if (fs::exists(dir + "/seal.json")) fs::rename(dir + "/seal.json", dir + "/seal.prev.json");
    write_file_atomic(dir + "/seal.json", text);
    for (auto& [path, c] : taken) carried_macs()[path] = std::move(c);
  } catch (const std::exception& e) {
    const std::string why = dir + "/seal.json: cannot be written: " + e.what();
    // At a checkpoint the folder stopped holding the run's records mid-run: exit 4, as for the
    // checkpoint itself (README, exit codes). Before the first phase the folder is the
    // configuration's --out, which could not be written: exit 2.
    if (checkpoint_text) throw std::runtime_error(why);
    throw ConfigError(why);
  }
}

std::vector<std::string> records_unlike_their_seal(const std::string& dir, const seal::Key& k,
                                                   const std::vector<std::string>& records) {
  const seal::Check c = seal::check_seal(dir, dir + "/seal.json", k);
  if (c.files.empty() && !c.problems.empty()) return {c.problems.front()};  // the seal itself no longer holds
  std::vector<std::string> unlike;
  for (const auto& [rel, state] : c.files)
    if ((state == seal::FileState::Changed || state == seal::FileState::NotRegular) &&
        std::find(records.begin(), records.end(), rel) != records.end())
      unlike.push_back(rel + ": " + seal::to_string(state));
  return unlike;
}

void drop_previous_seal(const std::string& dir) {
  std::error_code ec;
  fs::remove(dir + "/seal.prev.json", ec);
}

std::vector<std::string> sealed_files(const std::string& dir) {
  std::vector<std::string> out;
  try {
    std::ifstream in(dir + "/seal.json");
    const nlohmann::json j = parse_json_unique_keys(in);
    for (const auto& [rel, mac] : j.at("files").items()) out.push_back(rel);
  } catch (const std::exception&) {
    out.clear();
  }
  return out;
}

namespace {

// A seal holds for a resume when it is this key's, its list is whole, it covers what a resume
// reads, and every file it lists that a resume reads is as sealed (the loop test's records too:
// loop-figures computes from them).
bool holds_for_resume(const seal::Check& c, std::string& why) {
  std::vector<std::string> bad;
  for (const std::string& p : c.problems) {
    const std::string rel = p.substr(0, p.find(':'));
    const bool output = std::any_of(c.files.begin(), c.files.end(), [&](const auto& f) { return f.first == rel; }) &&
                        written_by_every_ending(rel);  // a resume writes it again, never reads it
    if (!output) bad.push_back(p);
  }
  for (const std::string& p : bad) why += (why.empty() ? "" : "; ") + p;
  return bad.empty();
}

}  // namespace

std::optional<std::string> seal_in(const std::string& dir) {
  for (const char* name : {"seal.json", "seal.prev.json"})
    if (fs::exists(fs::symlink_status(dir + "/" + name))) return name;
  return std::nullopt;
}

bool check_seal_before_resume(const std::string& dir, const std::optional<seal::Key>& k, bool pending_ending,
                              bool ended_for_good) {
  const std::optional<std::string> seal_there = seal_in(dir);
  const bool sealed = seal_there.has_value();
  if (!k) {
    if (sealed)  // the seal that is there named
      throw ConfigError(dir + " is sealed (" + *seal_there + "): resume it with the station's key (--seal-key FILE or "
                              "RIG_SEAL_KEY); without it the resumed run could not be sealed");
    return false;
  }
  if (!sealed)
    throw ConfigError(dir + " is not sealed (no seal.json): the key cannot vouch for files it never sealed; resume "
                            "it without --seal-key (it stays unsealed) or start a new run");
  // The rig makes no links: a link in a sealed folder could point the resume at what the seal
  // never saw.
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it)
    if (it->is_symlink())
      throw ConfigError(it->path().string() + ": a symbolic link in a sealed run folder (the rig makes none; what "
                                              "a link points at could change without the seal)");
  std::vector<std::string> must = {"run.json", "profile.toml"};
  if (fs::exists(Executive::checkpoint_path(dir))) must.push_back("checkpoint.json");
  std::string why;
  for (const char* name : {"seal.json", "seal.prev.json"}) {
    const std::string path = dir + "/" + name;
    if (!fs::exists(path)) continue;  // (a link was refused above)
    const seal::Check c = seal::check_seal(dir, path, *k, must);
    std::string w;
    if (holds_for_resume(c, w)) {
      // Its ending stopped after the seal: the history row (or the page) is what is left, done
      // from the passport the seal vouches for.
      const bool passport_sealed = std::any_of(c.files.begin(), c.files.end(), [](const auto& e) {
        return e.first == "passport.json" && e.second == seal::FileState::Ok;
      });
      const bool finish = pending_ending && name == std::string("seal.json") && passport_sealed;
      const bool final_outcome = is_verdict(c.outcome) ||
                                 (ended_for_good && (c.outcome == "ERROR" || c.outcome == "ABORTED"));
      // A final ending is finished from the files its seal vouches for, and sealed again with the
      // page: every one must be as sealed, the ending's own too, which a resume that computes
      // would write again (a code review: a junit.xml edited to PASS beside an ERROR passport
      // was sealed again, and `rig verify` then vouched for it).
      // The page aside: drawn from the passport, sealed again only where the finish draws it, and
      // a technician's `rig report --force` redraws it (its warning says `rig verify` then names it).
      std::vector<std::string> changed;
      for (const auto& [rel, state] : c.files)
        if (state != seal::FileState::Ok && rel != "report.html") changed.push_back(rel + ": " + seal::to_string(state));
      if (finish && final_outcome && !changed.empty())
        throw ConfigError(fmt::format("{}: its ending is final, and what its seal vouches for does not hold ({}): "
                                      "nothing done (the folder was changed outside the rig)",
                                      dir, fmt::join(changed, "; ")));
      if (is_verdict(c.outcome)) {
        if (finish) return true;
        throw ConfigError(dir + ": the run is complete: its seal states the outcome " + c.outcome +
                          " (whatever passport.json says now); nothing to resume");
      }
      return finish && final_outcome;
    }
    why += (why.empty() ? "" : "; ") + std::string(name) + ": " + w;
  }
  const bool other_key = why.find("sealed with another key") != std::string::npos;
  throw ConfigError(dir + ": the station's seal does not hold (" + why + "): " +
                    (other_key ? "resume with the key it was sealed with"
                               : "the folder was changed outside the rig; start a new run"));
}

std::optional<nlohmann::json> read_passport(const std::string& dir) {
  const std::string path = dir + "/passport.json";
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return std::nullopt;
  try {
    std::ifstream in(path);
    nlohmann::json j = parse_json_unique_keys(in);
    if (!j.is_object()) return std::nullopt;
    return j;
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::optional<std::string> passport_outcome(const std::string& dir) {
  const std::optional<nlohmann::json> j = read_passport(dir);
  if (!j || !j->contains("outcome") || !(*j)["outcome"].is_string()) return std::nullopt;
  return (*j)["outcome"].get<std::string>();
}

std::string verdict_of(const std::string& dir) {
  const std::optional<std::string> o = passport_outcome(dir);
  return o && is_verdict(*o) ? *o : "";
}

std::string earlier_log_missing_lines(const std::string& dir) {
  const std::optional<nlohmann::json> j = read_passport(dir);
  if (!j) return "";
  const nlohmann::json outcome = j->value("outcome", nlohmann::json()), why = j->value("aborted_reason", nlohmann::json());
  if (outcome != "ERROR" && outcome != "ABORTED") return "";
  return why.is_string() && why.get<std::string>().find(kLogMissingLines) != std::string::npos ? why.get<std::string>()
                                                                                                : "";
}

std::string final_outcome_of(const std::string& dir) {
  const std::string o = passport_outcome(dir).value_or("");
  if (is_verdict(o)) return o;
  return earlier_log_missing_lines(dir).empty() ? "" : o;
}

bool a_resume_finishes(const std::string& dir, const std::vector<std::string>& steps) {
  // Only the checkpoint says the log is short (the passport in place is none, or an earlier
  // attempt's): the resume is refused, and no ending is final to finish.
  if (earlier_log_missing_lines(dir).empty()) return checkpoint_log_missing_lines(dir).empty();
  const auto listed = [&steps](const char* step) { return std::find(steps.begin(), steps.end(), step) != steps.end(); };
  if (listed(kStepEnding)) return false;
  if (!listed(kStepSeal)) return true;
  // `seal` listed beside this ending's final seal in place (a stop before the list was brought up
  // to date): done already. This ending's: it states the passport's outcome and lists the
  // passport (an earlier attempt's final seal does not take it); the resume holds the folder to
  // it before it trusts it.
  std::error_code ec;
  if (!fs::is_regular_file(fs::path(dir) / "seal.json", ec)) return false;
  std::ifstream in(fs::path(dir) / "seal.json");
  const nlohmann::json seal = nlohmann::json::parse(in, nullptr, false);
  return seal.is_object() && seal.contains("outcome") && seal["outcome"].is_string() &&
         seal["outcome"].get<std::string>() == passport_outcome(dir).value_or("") && seal.contains("files") &&
         seal["files"].is_object() && seal["files"].contains("passport.json");
}

bool all_files_hold(const seal::Check& c) {
  return !c.files.empty() &&
         std::all_of(c.files.begin(), c.files.end(), [](const auto& e) { return e.second == seal::FileState::Ok; });
}

bool final_seal_owed(const std::string& dir, const seal::Check& c, const seal::Key& key) {
  const std::vector<std::string> steps = pending_steps(dir).value_or(std::vector<std::string>{});
  if (c.ok || std::find(steps.begin(), steps.end(), kStepSeal) == steps.end()) return false;
  if (!c.files.empty()) return c.outcome.empty() && all_files_hold(c);
  std::error_code ec;
  if (fs::exists(fs::path(dir) / "seal.json", ec) || ec) return false;
  const seal::Check prev = seal::check_seal(dir, dir + "/seal.prev.json", key, {});
  return prev.outcome.empty() && all_files_hold(prev);
}

std::string seal_key_words(const std::string& seal_key) {
  const char* env = std::getenv("RIG_SEAL_KEY");
  return env && seal_key == env ? std::string() : " --seal-key " + shell_word(seal_key);
}

bool outside_the_seal(const std::string& rel) {
  static const std::regex set_aside(R"((captures/[^/]+\.cap|loop-test\.csv)\.interrupted-[0-9]+)");
  const std::string name = fs::path(rel).filename().string();
  return rel == "run.log" || rel == "seal.json" || rel == "seal.prev.json" || name.rfind('.', 0) == 0 ||
         rel.find("/.") != std::string::npos ||
         (name.size() > 4 && name.compare(name.size() - 4, 4, ".tmp") == 0) || std::regex_match(rel, set_aside);
}

}  // namespace rig::cli
