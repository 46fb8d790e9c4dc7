// Every gtest process works in a private temporary folder. Before the first test runs, TMPDIR
// is pointed at a fresh $TMPDIR/rig-test-XXXXXX, so std::filesystem::temp_directory_path(), the
// `rig` children the e2e tests spawn and the Python helpers they call all write inside it. When
// every test of the process passed, the folder goes; a failure keeps it and names it on stderr
// for the post-mortem. Without this a suite run left about 460 MB in /tmp (the paper campaign
// alone 235 MB), and CI's sanitizer pass, the second suite run on one disk, ran out of space.
#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <system_error>

#include <gtest/gtest.h>

namespace {

class PrivateTmp final : public ::testing::Environment {
 public:
  // In SetUp, not the constructor: gtest_discover_tests runs the binary only to list the tests,
  // and that run never tears the environment down.
  void SetUp() override {
    std::error_code ec;
    const auto parent = std::filesystem::temp_directory_path(ec);
    if (ec) return;
    std::string dir = (parent / "rig-test-XXXXXX").string();
    if (::mkdtemp(dir.data()) == nullptr) return;  // keep the inherited TMPDIR
    // 0711, not mkdtemp's 0700: as root, the PostgreSQL tests run initdb as `nobody` in a
    // folder below this one (tests/report/pg_server.hpp), and nobody must pass through.
    ::chmod(dir.c_str(), 0711);
    if (const char* old = std::getenv("TMPDIR")) inherited_ = old;
    root_ = dir;
    ::setenv("TMPDIR", root_.c_str(), 1);
    // Named now too: a crash, an ASan abort or a ctest timeout never reaches TearDown, and
    // ctest shows this output only for a test that failed.
    std::fprintf(stderr, "private_tmp: TMPDIR=%s\n", root_.c_str());
  }
  void TearDown() override {
    if (root_.empty()) return;
    if (inherited_) ::setenv("TMPDIR", inherited_->c_str(), 1);
    else ::unsetenv("TMPDIR");
    std::error_code ec;
    const bool passed = ::testing::UnitTest::GetInstance()->Passed();
    if (passed) std::filesystem::remove_all(root_, ec);
    if (!passed || ec)
      std::fprintf(stderr, "private_tmp: this process's files are kept in %s\n", root_.c_str());
    root_.clear();
    inherited_.reset();
  }

 private:
  std::string root_;
  std::optional<std::string> inherited_;
};

// gtest owns and deletes the environment.
[[maybe_unused]] const auto* const kRegistered = ::testing::AddGlobalTestEnvironment(new PrivateTmp);

}  // namespace
