// rig verify DIR --seal-key FILE: is the run folder as the station sealed it (docs/seal.md)?
#include <filesystem>
#include <iostream>
#include <memory>

#include <fmt/format.h>

#include "app/commands.hpp"
#include "app/run_seal.hpp"
#include "rig/core/errors.hpp"

namespace rig::cli {

namespace {

int do_verify(const std::string& dir, const std::string& key_path) {
  if (!std::filesystem::is_directory(dir)) throw ConfigError(dir + ": not a run folder");
  const std::optional<seal::Key> key = station_key(key_path);
  if (!key) throw ConfigError("rig verify needs the station's key: --seal-key FILE or RIG_SEAL_KEY");
  // The passport is what a seal is for: a folder whose seal leaves it out is not verified.
  const seal::Check c = seal::check_seal(dir, dir + "/seal.json", *key, {"passport.json"});
  std::cout << fmt::format("{}: seal.json, key {} ({})\n", dir, key->id, key->path);
  for (const std::string& f : c.files) {
    bool bad = false;
    for (const std::string& p : c.problems) bad = bad || p.rfind(f + ":", 0) == 0;
    std::cout << fmt::format("  {:<8} {}\n", bad ? "CHANGED" : "ok", f);
  }
  for (const std::string& p : c.problems) std::cout << "  problem: " << p << "\n";
  std::cout << (c.ok ? fmt::format("verified: {} files as the station sealed them\n", c.files.size())
                     : std::string("NOT verified: the folder is not as the station sealed it\n"));
  return c.ok ? kExitPass : kExitFail;
}

}  // namespace

void add_verify(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("verify", "Check a run folder against the station's seal (seal.json)");
  auto dir = std::make_shared<std::string>();
  auto key = std::make_shared<std::string>();
  sub->add_option("DIR", *dir, "Run folder")->required();
  sub->add_option("--seal-key", *key, "The station's key (HMAC-SHA256)")->envname("RIG_SEAL_KEY");
  sub->callback([dir, key, &rc] { rc = do_verify(*dir, *key); });
}

}  // namespace rig::cli
