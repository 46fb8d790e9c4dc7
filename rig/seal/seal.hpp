// The station's seal on a run folder: HMAC-SHA256 (RFC 2104, FIPS 198-1) of each file the run
// wrote, under a key only the station holds. A checkpoint is integrity-checked against its
// captures; the seal adds who wrote them: without the key, an edited profile, checkpoint,
// capture or passport cannot be given a matching seal (docs/seal.md).
// libcrypto (OpenSSL 3) is loaded when first used (a key, a run's profile_sha256), not linked:
// every rig command's start-up would otherwise map and relocate it.
#pragma once
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace rig::seal {

struct Key {
  std::string path;
  std::string bytes;
  std::string id;  // the first 16 hex digits of HMAC(key, "rig.seal key id"): names the key, reveals nothing
};

// A station key: a regular file of at least 32 bytes that its owner alone may read or write
// (mode 0600 or 0400). Anything else is ConfigError naming the file and what is wrong.
Key load_key(const std::string& path);

// HMAC-SHA256 of the file's bytes, lower-case hex; ConfigError naming an unreadable file.
std::string file_mac(const Key& k, const std::string& path);
std::string text_mac(const Key& k, const std::string& text);

// SHA-256 (FIPS 180-4) of `bytes`, lower-case hex: a keyless digest anyone can recompute with
// `sha256sum`, for naming a text (the passport's profile_sha256), not for vouching for it.
// ConfigError when libcrypto cannot be loaded.
std::string sha256_hex(std::string_view bytes);

struct Entry {
  std::string rel;   // path relative to the run folder, '/' separated
  std::string text;  // the bytes to seal when the file is not written yet (empty: read the file)
  bool from_text = false;
  std::string mac;   // its MAC, already taken (a record sealed once, carried to later seals): used as is
};

// seal.json's text (schema rig.seal/1) over `entries`: each file's MAC, the run's `outcome` as
// the passport states it (empty while the run goes on), and the seal's own MAC over both, so
// entries of different seals cannot be combined and a sealed verdict cannot be edited.
std::string make_seal(const std::string& dir, const Key& k, const std::vector<Entry>& entries,
                      const std::string& outcome = "");

enum class FileState { Ok, Changed, Missing, NotRegular };
inline const char* to_string(FileState f) {
  switch (f) {
    case FileState::Ok: return "ok";
    case FileState::Changed: return "changed since it was sealed";
    case FileState::Missing: return "sealed, but missing";
    case FileState::NotRegular: return "sealed as a file, now not a regular file";
  }
  return "?";
}

struct Check {
  bool ok = false;  // the seal is this key's, its own MAC holds, every file matches, every must_cover is sealed
  std::vector<std::pair<std::string, FileState>> files;  // what it covers, sorted by path, each as found
  std::vector<std::string> problems;  // one line each: "captures/raw-U10.cap: changed since it was sealed"
  std::string outcome;                // the sealed outcome (PASS, FAIL, ABORTED, ERROR; empty: not final)
};

// The end of check_seal's problem for a seal file that is not there (after its path): `rig verify`
// words it otherwise where the final seal is owed.
inline constexpr std::string_view kSealMissing = ": missing: the folder is not sealed";

// Checks `seal_path` (a seal.json) against the folder's files and the key; every file in
// `must_cover` must be among those sealed. Neither the seal nor a sealed file is opened unless it
// is a regular file (a FIFO put in its place cannot stall the check).
Check check_seal(const std::string& dir, const std::string& seal_path, const Key& k,
                 const std::vector<std::string>& must_cover = {});

}  // namespace rig::seal
