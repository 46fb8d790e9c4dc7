#include "rig/seal/seal.hpp"
#include "rig/core/json_unique.hpp"

#include <openssl/evp.h>
#include <openssl/params.h>
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "rig/core/errors.hpp"
#include "rig/core/escape.hpp"
#include "rig/core/lazy_library.hpp"

namespace rig::seal {

namespace {

constexpr const char* kSchema = "rig.seal/1";

// The six libcrypto calls a streaming HMAC needs (OpenSSL 3's EVP_MAC interface).
struct Crypto {
  decltype(&EVP_MAC_fetch) mac_fetch;
  decltype(&EVP_MAC_CTX_new) ctx_new;
  decltype(&EVP_MAC_CTX_free) ctx_free;
  decltype(&EVP_MAC_init) init;
  decltype(&EVP_MAC_update) update;
  decltype(&EVP_MAC_final) final_;
  decltype(&OSSL_PARAM_construct_utf8_string) param_string;
  decltype(&OSSL_PARAM_construct_end) param_end;
  decltype(&EVP_Digest) digest;
  decltype(&EVP_sha256) sha256;
  EVP_MAC* hmac = nullptr;
};

const Crypto& crypto() {
  static const std::optional<Crypto> api = []() -> std::optional<Crypto> {
    LazyLibrary lib("libcrypto.so.3");
    Crypto c{};
    lib.get(c.mac_fetch, "EVP_MAC_fetch");
    lib.get(c.ctx_new, "EVP_MAC_CTX_new");
    lib.get(c.ctx_free, "EVP_MAC_CTX_free");
    lib.get(c.init, "EVP_MAC_init");
    lib.get(c.update, "EVP_MAC_update");
    lib.get(c.final_, "EVP_MAC_final");
    lib.get(c.param_string, "OSSL_PARAM_construct_utf8_string");
    lib.get(c.param_end, "OSSL_PARAM_construct_end");
    lib.get(c.digest, "EVP_Digest");
    lib.get(c.sha256, "EVP_sha256");
    if (!lib.ok()) return std::nullopt;
    c.hmac = c.mac_fetch(nullptr, "HMAC", nullptr);
    if (!c.hmac) return std::nullopt;
    return c;
  }();
  if (!api) throw ConfigError("cannot load HMAC and SHA-256 from libcrypto.so.3 (Debian package libssl3): the run folder's seal and the passport's profile_sha256 need them");
  return *api;
}

std::string hex_of(const unsigned char* p, std::size_t n) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string s;
  for (std::size_t i = 0; i < n; ++i) s += kHex[p[i] >> 4], s += kHex[p[i] & 15];
  return s;
}

// One HMAC-SHA256 computation, fed in pieces.
class Mac {
 public:
  explicit Mac(const std::string& key) : c_(crypto()), ctx_(c_.ctx_new(c_.hmac), c_.ctx_free) {
    char digest[] = "SHA256";
    OSSL_PARAM params[] = {c_.param_string("digest", digest, 0), c_.param_end()};
    if (!ctx_ || !c_.init(ctx_.get(), reinterpret_cast<const unsigned char*>(key.data()), key.size(), params))
      throw std::runtime_error("HMAC-SHA256 could not be started (libcrypto)");
  }
  void add(const char* p, std::size_t n) {
    if (n && !c_.update(ctx_.get(), reinterpret_cast<const unsigned char*>(p), n))
      throw std::runtime_error("HMAC-SHA256 update failed (libcrypto)");
  }
  std::string hex() {
    unsigned char out[32];
    std::size_t n = 0;
    if (!c_.final_(ctx_.get(), out, &n, sizeof out) || n != sizeof out)
      throw std::runtime_error("HMAC-SHA256 could not be finished (libcrypto)");
    return hex_of(out, sizeof out);
  }

 private:
  const Crypto& c_;
  std::unique_ptr<EVP_MAC_CTX, decltype(&EVP_MAC_CTX_free)> ctx_;
};

// What the seal's own MAC covers: the schema, the key's id and every (path, MAC), sorted.
std::string seal_body(const std::string& key_id, const std::string& outcome,
                      const std::vector<std::pair<std::string, std::string>>& files) {
  std::string s = std::string(kSchema) + "\n" + key_id + "\n" + outcome + "\n";
  for (const auto& [rel, mac] : files) s += rel + "\t" + mac + "\n";
  return s;
}

}  // namespace

std::string sha256_hex(std::string_view bytes) {
  const Crypto& c = crypto();
  unsigned char out[32];
  unsigned int n = 0;
  if (!c.digest(bytes.data(), bytes.size(), out, &n, c.sha256(), nullptr) || n != sizeof out)
    throw std::runtime_error("SHA-256 failed (libcrypto)");
  return hex_of(out, sizeof out);
}

std::string text_mac(const Key& k, const std::string& text) {
  Mac m(k.bytes);
  m.add(text.data(), text.size());
  return m.hex();
}

std::string file_mac(const Key& k, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot be read to seal or check it");
  Mac m(k.bytes);
  std::vector<char> buf(1 << 20);
  while (in) {
    in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
    m.add(buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw ConfigError(path + ": read error while sealing or checking it");
  return m.hex();
}

Key load_key(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw ConfigError(path + ": station key not found");
  if (!S_ISREG(st.st_mode)) throw ConfigError(path + ": station key is not a regular file");
  if ((st.st_mode & 077) != 0)
    throw ConfigError(path + ": station key may be read or written by others (mode " +
                      [&] {
                        char b[8];
                        std::snprintf(b, sizeof b, "%04o", static_cast<unsigned>(st.st_mode & 07777));
                        return std::string(b);
                      }() +
                      "): chmod 600 it; a key others can read seals nothing");
  std::ifstream in(path, std::ios::binary);
  Key k;
  k.path = path;
  k.bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) throw ConfigError(path + ": station key cannot be read");
  if (k.bytes.size() < 32)
    throw ConfigError(path + ": station key has " + std::to_string(k.bytes.size()) +
                      " bytes; at least 32 are needed (head -c 32 /dev/urandom > " + path + ")");
  k.id = text_mac(k, "rig.seal key id").substr(0, 16);
  return k;
}

std::string make_seal(const std::string& dir, const Key& k, const std::vector<Entry>& entries,
                      const std::string& outcome) {
  std::vector<std::pair<std::string, std::string>> files;
  for (const Entry& e : entries)
    files.emplace_back(e.rel, !e.mac.empty() ? e.mac : e.from_text ? text_mac(k, e.text) : file_mac(k, dir + "/" + e.rel));
  std::sort(files.begin(), files.end());
  nlohmann::ordered_json j;
  j["schema"] = kSchema;
  j["algorithm"] = "HMAC-SHA256";
  j["key_id"] = k.id;
  j["outcome"] = outcome;
  j["files"] = nlohmann::ordered_json::object();
  for (const auto& [rel, mac] : files) j["files"][rel] = mac;
  j["seal"] = text_mac(k, seal_body(k.id, outcome, files));
  return j.dump(1);
}

namespace {

bool regular_file(const std::string& path, bool& exists) {
  struct stat st {};
  exists = ::lstat(path.c_str(), &st) == 0;
  return exists && S_ISREG(st.st_mode);
}

}  // namespace

Check check_seal(const std::string& dir, const std::string& seal_path, const Key& k,
                 const std::vector<std::string>& must_cover) {
  Check c;
  bool exists = false;
  if (!regular_file(seal_path, exists)) {
    c.problems.push_back(seal_path + (exists ? std::string(": not a regular file") : std::string(kSealMissing)));
    return c;
  }
  std::ifstream in(seal_path, std::ios::binary);
  nlohmann::json j;
  try {
    j = parse_json_unique_keys(in);  // two MACs for one file: refused, not the last taken
  } catch (const std::exception& e) {
    c.problems.push_back(seal_path + ": unreadable: " + e.what());
    return c;
  }
  if (!j.is_object() || !j.contains("schema") || j["schema"] != kSchema || !j.contains("files") || !j["files"].is_object() ||
      !j.contains("seal") || !j["seal"].is_string() || !j.contains("key_id") || !j["key_id"].is_string() ||
      !j.contains("outcome") || !j["outcome"].is_string()) {
    c.problems.push_back(seal_path + ": not a rig.seal/1 seal");
    return c;
  }
  if (j["key_id"] != k.id) {
    c.problems.push_back(seal_path + ": sealed with another key (key_id " + j["key_id"].get<std::string>() +
                         "; " + k.path + " is " + k.id + ")");
    return c;
  }
  // The text the seal's MAC covers lists "path TAB mac NL": only a seal whose paths and outcome
  // hold no control character and whose MACs are 64 hex digits reads back to one list. Without
  // this, two entries could be folded into one whose path held "TAB mac NL" (the same text, the
  // same MAC, no key needed) and both files deleted: rig verify said "verified" (an auditor's
  // review). Nor does a seal carry a field rig does not write, or another algorithm's name.
  const auto plain = [](const std::string& t) {
    return std::none_of(t.begin(), t.end(), [](char ch) { return static_cast<unsigned char>(ch) < 0x20 || ch == 0x7F; });
  };
  const auto a_mac = [](const std::string& t) {
    return t.size() == 64 && std::all_of(t.begin(), t.end(), [](char ch) { return (ch >= '0' && ch <= '9') || (ch >= 'a' && ch <= 'f'); });
  };
  for (const auto& [field, value] : j.items())
    if (field != "schema" && field != "algorithm" && field != "key_id" && field != "outcome" && field != "files" &&
        field != "seal") {
      c.problems.push_back(seal_path + ": field '" + shown_text(field) + "' is not a rig.seal/1 field");
      return c;
    }
  if (j.contains("algorithm") && j["algorithm"] != "HMAC-SHA256") {
    c.problems.push_back(seal_path + ": algorithm " + shown_text(j["algorithm"].dump()) + ": rig seals with HMAC-SHA256");
    return c;
  }
  if (!plain(j["outcome"].get<std::string>())) {
    c.problems.push_back(seal_path + ": outcome '" + shown_text(j["outcome"].get<std::string>()) +
                         "': a control character, which rig never writes");
    return c;
  }
  std::vector<std::pair<std::string, std::string>> files;
  for (const auto& [rel, mac] : j["files"].items()) {
    if (!mac.is_string() || !a_mac(mac.get<std::string>())) {
      c.problems.push_back(seal_path + ": files." + shown_text(rel) + ": not a MAC (64 hex digits)");
      return c;
    }
    if (rel.empty() || !plain(rel)) {
      c.problems.push_back(seal_path + ": files.'" + shown_text(rel) + "': not a path rig seals (" +
                           (rel.empty() ? "empty" : "a control character") + ")");
      return c;
    }
    files.emplace_back(rel, mac.get<std::string>());
  }
  std::sort(files.begin(), files.end());
  if (text_mac(k, seal_body(k.id, j["outcome"].get<std::string>(), files)) != j["seal"].get<std::string>()) {
    c.problems.push_back(seal_path + ": the seal's own MAC does not hold: its list of files or its outcome was edited");
    return c;
  }
  c.outcome = j["outcome"].get<std::string>();
  for (const auto& [rel, mac] : files) {
    FileState f = FileState::Ok;
    if (!regular_file(dir + "/" + rel, exists)) f = exists ? FileState::NotRegular : FileState::Missing;
    else {
      try {
        if (file_mac(k, dir + "/" + rel) != mac) f = FileState::Changed;
      } catch (const ConfigError&) {
        f = FileState::NotRegular;
      }
    }
    c.files.emplace_back(rel, f);
    if (f != FileState::Ok) c.problems.push_back(rel + ": " + to_string(f));
  }
  // One the folder does not even hold is said so (a killed run has no passport yet; "not sealed"
  // read as if one were there, a review).
  for (const std::string& rel : must_cover)
    if (std::none_of(c.files.begin(), c.files.end(), [&](const auto& e) { return e.first == rel; })) {
      bool there = false;
      regular_file(dir + "/" + rel, there);  // lstat: never throws (a code review)
      c.problems.push_back(rel + (there ? ": not sealed" : ": not sealed (the folder has none)"));
    }
  c.ok = c.problems.empty();
  return c;
}

}  // namespace rig::seal
