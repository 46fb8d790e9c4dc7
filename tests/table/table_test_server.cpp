// A table emulator served over Modbus in its own process, so a test can kill
// it mid-move (SIGKILL). Usage: table_test_server SPEC [TOML-TEXT]
// Prints "listening <endpoint>" once serving, then serves until killed.
#include <csignal>
#include <exception>
#include <memory>
#include <cstdio>
#include <string>
#include <thread>

#include "plant/table/table_server.hpp"
#include "rig/core/toml_util.hpp"

int main(int argc, char** argv) {
  const std::string first = argc > 1 ? argv[1] : "";
  bool help = false;  // --help in either place: as TOML it would be a parse error
  for (int i = 1; i < argc; ++i) help = help || std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h";
  if (argc < 2 || argc > 3 || help) {
    std::fprintf(argc < 2 || argc > 3 ? stderr : stdout,
                 "usage: %s SPEC [TOML]\n  SPEC  tcp:HOST:PORT (port 0: any free one) or rtu:DEVICE[,BAUD...]\n"
                 "  TOML  [plant.table] keys as text, e.g. 'velocity_dps = 90.0'\n",
                 argv[0]);
    return argc < 2 || argc > 3 ? 2 : 0;
  }
  std::unique_ptr<rig::plant::TableEmulator> emu;
  std::unique_ptr<rig::plant::TableServer> server;
  try {
    const toml::table cfg = rig::cfg::parse_string(argc > 2 ? argv[2] : "", "argv");
    emu = rig::plant::make_table_emulator(&cfg, 1);
    server = std::make_unique<rig::plant::TableServer>(*emu, first);
    server->start();
  } catch (const std::exception& e) {  // a bad SPEC or TOML, a port in use
    std::fprintf(stderr, "table_test_server: %s\n", e.what());
    return 2;
  }
  rig::plant::TableServer& srv = *server;
  std::printf("listening %s\n", srv.endpoint().c_str());
  std::fflush(stdout);
  for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}
