// Each `rig` subcommand lives in its own file and registers itself here.
// A command's callback stores its exit code (rig::ExitCode) in `rc`.
#pragma once
#include <CLI/CLI.hpp>

namespace rig::cli {

void add_run(CLI::App& app, int& rc);       // cmd_run.cpp      the acceptance procedure
void add_analyze(CLI::App& app, int& rc);   // cmd_analyze.cpp  Allan/PSD analysis of a recording
void add_plant(CLI::App& app, int& rc);     // cmd_plant.cpp    emulated table + DUT as endpoints
void add_table(CLI::App& app, int& rc);     // cmd_table.cpp    manual table control (Modbus)
void add_dut(CLI::App& app, int& rc);       // cmd_dut.cpp      manual DUT control (CAN)
void add_filter(CLI::App& app, int& rc);    // cmd_filter.cpp   output-filter evaluation/selection
void add_report(CLI::App& app, int& rc);    // cmd_report.cpp   report.html from a run folder
void add_history(CLI::App& app, int& rc);   // cmd_history.cpp  results database queries
void add_capture(CLI::App& app, int& rc);   // cmd_capture.cpp  capture files from candump logs
void add_verify(CLI::App& app, int& rc);    // cmd_verify.cpp   a run folder against the station's seal

}  // namespace rig::cli
