// The history database a command records to or reads when it is given none (no --db, no
// hardware file's [history] url): history::default_db_url, with the environment's mistakes
// named where they come from (docs/history.md, "Where the database is").
#pragma once
#include <string>

namespace rig::cli {

struct HistorySource {
  std::string url;
  bool from_rig_history = false;  // $RIG_HISTORY's: its errors, later too, say "RIG_HISTORY: ..."
};

// $RIG_HISTORY (a URL rig cannot open is exit 2 saying "RIG_HISTORY: ..."), else the rig
// config's [history] url (the file holds [history] only: an unknown section or key, or a URL rig
// cannot open, is exit 2 naming FILE:LINE:COL), else the user's default database.
HistorySource default_history();

}  // namespace rig::cli
