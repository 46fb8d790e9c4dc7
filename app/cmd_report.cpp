// `rig report DIR`: (re)writes DIR/report.html from a finished or aborted run's folder.
#include <iostream>
#include <optional>

#include "app/commands.hpp"
#include "app/folder_lock.hpp"
#include "app/passport_held.hpp"
#include "rig/core/errors.hpp"
#include "rig/core/path_kind.hpp"
#include "rig/report/passport_read.hpp"
#include "rig/report/report.hpp"

namespace rig::cli {

void add_report(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("report", "Write report.html (passport, plots; prints on A4) from a run folder");
  auto dir = std::make_shared<std::string>();
  sub->add_option("DIR", *dir, "Run folder holding passport.json (and analysis.json)")->required();
  auto force = std::make_shared<bool>(false);
  sub->add_flag("--force", *force,
                "Write a sealed folder's report.html even where it comes out other than the sealed page (rig verify "
                "then names it changed)");
  sub->footer("Exit codes: 0 written; 2 passport.json missing, malformed, or with verdicts its own values and "
              "limits contradict (the file and field are named), a rig run using the folder now, or a sealed "
              "report.html the page would change (without --force).");
  sub->callback([&rc, dir, force] {
    // A run or resume holding the folder writes its own report at its end; its passport may be
    // missing or about to change now (a review read "does the run folder exist?" there). The
    // lock is held while the report is written, so no run takes the folder half-way (a check
    // alone left that window, a code review). A path that is no folder is named by the reader.
    std::optional<FolderLock> lock;
    if (path_kind(*dir, "rig report") == PathKind::directory) lock.emplace(*dir, "rig report " + *dir, false);
    // A passport is drawn only as its run wrote it: its limits its folder's profile.toml's, its
    // junit.xml agreeing (a technician's review: a FAIL edited to PASS, its limit loosened with
    // it, was drawn PASS). Sealed or not: a seal file is not checked here (no key), and an empty
    // one in the folder let the edit by (a re-test); `rig verify` says who wrote the bytes.
    if (lock)
      if (const std::string why = passport_unlike_its_folder(*dir, report::read_passport(*dir)); !why.empty())
        throw ConfigError(*dir + "/passport.json: " + why + ": the passport was changed after its run wrote it; "
                          "report.html not written");
    std::cout << report::write_report(*dir, *force) << "\n";
    rc = kExitPass;
  });
}

}  // namespace rig::cli
