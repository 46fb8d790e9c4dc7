// A table emulator served over Modbus in its own process, so a test can kill
// it mid-move (SIGKILL). Usage: table_test_server SPEC [TOML-TEXT]
// Prints "listening <endpoint>" once serving, then serves until killed.
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "plant/table/table_server.hpp"
#include "rig/core/toml_util.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SPEC [TOML]\n", argv[0]);
    return 2;
  }
  const toml::table cfg = rig::cfg::parse_string(argc > 2 ? argv[2] : "", "argv");
  auto emu = rig::plant::make_table_emulator(&cfg, 1);
  rig::plant::TableServer server(*emu, argv[1]);
  server.start();
  std::printf("listening %s\n", server.endpoint().c_str());
  std::fflush(stdout);
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}
