#include "rig/cli/commands.hpp"
#include "rig/core/errors.hpp"

#include <iostream>

namespace rig::cli {

void add_filter(CLI::App& app, int& rc) {
  auto* sub = app.add_subcommand("filter", "(not built yet)");
  sub->callback([&rc] {
    std::cerr << "rig filter: not available in this build\n";
    rc = kExitUsage;
  });
}

}  // namespace rig::cli
