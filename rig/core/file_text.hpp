// A small file's whole text, for the files a run folder holds (run.json, a checkpoint, a profile,
// junit.xml): "" where it cannot be read, whose own check (a parse, a comparison) then says why.
#pragma once
#include <fstream>
#include <sstream>
#include <string>

namespace rig {

inline std::string file_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace rig
