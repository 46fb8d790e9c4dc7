#include "app/run_folder.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <cstring>
#include <cctype>
#include <ctime>
#include <fstream>
#include <iostream>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "rig/core/errors.hpp"
#include "rig/core/json_unique.hpp"
#include "rig/core/escape.hpp"

namespace rig::cli {

namespace fs = std::filesystem;

namespace {
// The default run folder's time stamp: ISO 8601 basic time, UTC, e.g. 2026-11-23T205900Z.
// No colons, so a run folder copies to FAT and Windows shares; still sorts by time.
std::string folder_time_utc() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  ::gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H%M%SZ", &tm);
  return buf;
}

}  // namespace

// The run folder must be creatable and writable before any device opens: a bad --out is
// the operator's configuration (exit 2), not a fault of the rig (exit 4).
// `option`: the option that named the folder (--out, or --resume: a read-only folder's resume
// said "--out DIR", an option it was not given, a review).
// A folder name longer than a file system takes (NAME_MAX, 255 bytes): said as such by the dry
// run too, which passed it before (a review).
// The whole path too: with the run's own files in it (captures/in-run-U10.cap.interrupted-12 and
// the like, up to kRunFileRoom bytes) it must stay under PATH_MAX (a re-test: a 4266-byte --out
// passed the dry run; one of 4080 bytes was created, then called "not writable").
constexpr std::size_t kRunFileRoom = 64;
void refuse_a_name_too_long(const std::string& dir, const std::string& option) {
  const std::size_t cut = dir.size() <= 80 ? dir.size() : utf8_cut(dir, 80);
  const std::string shown = shown_text(dir.substr(0, cut)) + (cut < dir.size() ? "..." : "");
  for (const fs::path& part : fs::path(dir))
    if (part.native().size() > 255)
      throw ConfigError(fmt::format("{} {}: a folder name of {} bytes; a file system takes 255 at most", option, shown,
                                    part.native().size()));
  std::error_code ec;
  const std::size_t whole = fs::absolute(dir, ec).native().size();
  if (whole + kRunFileRoom >= PATH_MAX)
    throw ConfigError(fmt::format("{} {}: a path of {} bytes; with the run's own files in it ({} bytes more) it must "
                                  "stay under {} (PATH_MAX)",
                                  option, shown, whole, kRunFileRoom, PATH_MAX));
}

void prepare_run_folder(const std::string& dir, const std::string& option) {
  std::error_code ec;
  refuse_a_name_too_long(dir, option);
  fs::create_directories(dir, ec);
  if (ec) throw ConfigError(option + " " + dir + ": cannot create the run folder: " + ec.message());
  const std::string probe = dir + "/.rig-write-check-" + std::to_string(::getpid());
  std::ofstream(probe) << "rig\n";
  const bool writable = fs::file_size(probe, ec) == 4 && !ec;
  fs::remove(probe, ec);
  if (!writable) throw ConfigError(option + " " + dir + ": the run folder is not writable");
}

void refuse_a_run_log_it_cannot_write(const std::string& dir) {
  const std::string path = dir + "/run.log";
  struct stat st {};
  // None (the run makes it), or not a file (refuse_non_files names it; a FIFO would block the open).
  if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return;
  // Opened as the run opens it, and closed unwritten: its contents and times stay as they were
  // (O_NONBLOCK: a FIFO put there since the lstat does not hold the open).
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd >= 0) {
    ::close(fd);
    return;
  }
  throw ConfigError(fmt::format("{}: cannot be opened to write the run's account ({}): nothing was started or "
                                "changed; run the command again once it can be written",
                                path, std::strerror(errno)));
}

bool holds_a_rig_run(const fs::path& d) {
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(d / "run.json", ec))) return false;
  try {
    std::ifstream in(d / "run.json");
    const nlohmann::json j = parse_json_unique_keys(in);
    return j.is_object() && j.contains("software") && j["software"].is_string() &&
           j["software"].get<std::string>().starts_with("rig ");
  } catch (const std::exception&) {
    return false;
  }
}

void refuse_a_folder_a_new_run_cannot_own(const std::string& dir, const std::string& option, bool sealed,
                                          bool taken_over) {
  std::error_code ec;
  const fs::path here = fs::absolute(dir, ec).lexically_normal();
  for (fs::path up = here.parent_path(); !up.empty(); up = up.parent_path()) {
    if (holds_a_rig_run(up))
      throw ConfigError(fmt::format("{} {}: inside the run folder {} (it holds run.json): a run there adds its files "
                                    "to that run's (a sealed one then fails rig verify); choose an {} outside it",
                                    option, shown_text(dir), shown_text(up.string()), option));
    if (up == up.root_path()) break;
  }
  if (!sealed || taken_over || !fs::is_directory(here, ec)) return;
  std::vector<std::string> names;
  std::size_t count = 0;
  // A hidden file (.gitkeep) is left alone, as rig verify leaves it (a note, not a failure); not a
  // hidden link or folder, which a sealed run's resume refuses (a link there, or in it).
  for (const auto& e : fs::directory_iterator(here, ec)) {
    const std::string name = e.path().filename().string();
    if (name.starts_with(".") && fs::is_regular_file(fs::symlink_status(e.path(), ec))) continue;
    if (++count <= 5) names.push_back(shown_text(name));
  }
  if (count == 0) return;
  throw ConfigError(fmt::format("{} {} holds {}{}, which the run does not write: a sealed run's folder holds its own "
                                "files only (rig verify names any other as not sealed); move {} or choose a new or "
                                "empty {}",
                                option, shown_text(dir), fmt::join(names, ", "),
                                count > names.size() ? fmt::format(" and {} more", count - names.size()) : "",
                                count == 1 ? "it" : "them", option));
}

// Whether this process can create a file in the existing directory `d`.
bool can_create_file_in(const fs::path& d) {
  int fd = ::open(d.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0600);
  if (fd >= 0) {
    ::close(fd);
    return true;
  }
  if (errno != EOPNOTSUPP && errno != EISDIR) return false;  // EISDIR: a kernel without O_TMPFILE
  const fs::path probe = d / (".rig-write-check-" + std::to_string(::getpid()));
  fd = ::open(probe.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0600);
  if (fd < 0) return false;
  ::close(fd);
  ::unlink(probe.c_str());
  return true;
}

// `p` itself, or its nearest ancestor that exists: where a folder that is not there yet would be
// created.
fs::path nearest_existing(fs::path p) {
  std::error_code ec;
  while (!fs::exists(p, ec) && p.has_parent_path() && p != p.parent_path()) p = p.parent_path();
  return p;
}

// What the run's recordings take on disk: every sample is a 16-byte record of its capture
// (docs/capture-format.md); analysis.json and checkpoint.json grow with them (a tenth), and they,
// report.html and loop-test.csv take about 2 MB on the shortest profile (the `paper` profile: 103
// MB of captures, 109-114 MB in all; ci 2 MB, 3.8 MB: a re-test found 1.1x + 1 MB short there).
// Retries of a capture are not counted.
double recorded_seconds(const acceptance::Profile& p) {
  return static_cast<double>(p.order.size()) * p.run_s + p.in_run_s + p.raw_s;
}
std::uint64_t recordings_bytes(const acceptance::Profile& p) {
  return static_cast<std::uint64_t>(16 * p.rate_hz * recorded_seconds(p) * 1.1) + 3'000'000;
}

// The room the run folder has: free bytes for this process on the file system of `dir` (its
// nearest existing ancestor), compared with the profile's recordings. A new run that cannot fit
// is refused before anything opens (a technician's review: a `paper` run into a folder with
// 100 MB free stopped at its 30-minute capture, 50 minutes of bench time lost); a resume (which
// records less) is warned. Returns the line the dry run prints.
std::string check_room(const std::string& dir, const std::string& option, const acceptance::Profile& p, bool resume) {
  std::error_code ec;
  const fs::path at = nearest_existing(fs::absolute(dir, ec));
  struct statvfs v {};
  if (::statvfs(at.c_str(), &v) != 0) return "";
  // Root writes into the blocks a file system reserves for it (the run would fit there).
  const std::uint64_t free = static_cast<std::uint64_t>(::geteuid() == 0 ? v.f_bfree : v.f_bavail) * v.f_frsize,
                      need = recordings_bytes(p);
  // The need rounded up, the room down: "4 MB free ... take about 4 MB ... would stop" read as a
  // contradiction (a re-test).
  auto mb_up = [](std::uint64_t b) { return fmt::format("{:.0f} MB", std::ceil(static_cast<double>(b) / 1e6)); };
  auto mb_down = [](std::uint64_t b) { return fmt::format("{:.0f} MB", std::floor(static_cast<double>(b) / 1e6)); };
  const std::string line = fmt::format("Disk: the recordings take about {}{}; {} free on the file system of {}",
                                       mb_up(need), resume ? " for a whole run (a resume records only what is left)" : "",
                                       mb_down(free), at.string());
  if (free >= need) return line;
  const std::string why = fmt::format(
      "{} {}: {} free on its file system ({}), and the profile's recordings take about {} ({:.0f} s of samples at {:g} "
      "Hz, 16 bytes each, and the analysis): the run would stop when the disk is full",
      option, shown_text(dir), mb_down(free), at.string(), mb_up(need), recorded_seconds(p), p.rate_hz);
  if (!resume) throw ConfigError(why + "; free space, or give --out on another file system");
  std::cerr << "rig: warning: " << why << " if it records all of it\n";
  return line;
}

// A serial or profile name as one component of the default run folder's name: a '/' or a
// leading '.' ('../../x') would put the run outside runs/; those and other characters a shell
// or a file system treats specially become '_'. At most kFolderNamePart bytes: a file name
// holds 255 (NAME_MAX), and a long UTF-8 profile name passed the dry run, then the run ended
// "File name too long" with an empty runs/ (a review); the time and a -N follow it.
constexpr std::size_t kFolderNamePart = 128;
std::string folder_name_part(std::string s) {
  for (char& c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) c = '_';
  if (s.empty() || s[0] == '.') s.insert(s.begin(), '_');
  if (s.size() > kFolderNamePart) s.resize(kFolderNamePart);
  return s;
}

// runs/<name>-<UTC time to the second>; a second run started in the same second (a script, a
// line's next DUT with the same profile, two started at once) gets -2, -3, ..., not the first
// run's folder: each name is claimed by creating it (create_directory is atomic), not by looking.
std::string default_run_folder(const std::string& name) {
  const std::string base = fmt::format("runs/{}-{}", name, folder_time_utc());
  std::error_code ec;
  fs::create_directories("runs", ec);  // (a runs/ that cannot be made is named by prepare_run_folder)
  for (int i = 1; i < 10000; ++i) {
    const std::string dir = i == 1 ? base : fmt::format("{}-{}", base, i);
    if (fs::create_directory(dir, ec) || ec) return dir;  // claimed, or a cause prepare_run_folder names
  }
  return base;  // 10000 runs in one second: the guard refuses the first one's folder
}

}  // namespace rig::cli
