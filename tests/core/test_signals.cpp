// SignalWatcher (rig/executive/signals.hpp): SIGINT, SIGTERM, SIGHUP and SIGQUIT become a cancellation, and
// none is left pending when the watcher goes (its destructor unblocks them: a pending one would
// then end the process by its default action, after the run had finished).
#include <gtest/gtest.h>

#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "rig/executive/signals.hpp"

namespace rig {
namespace {

// A signal sent to this thread alone (raise) is not one the watcher's own thread can read: only
// the destructor's last look takes it. A code review found the process killed by a SIGINT that
// arrived as the destructor woke the watcher.
TEST(SignalWatcher, ASignalStillPendingAtTheEndIsTakenNotLeftToEndTheProcess) {
  CancelSource source;
  {
    SignalWatcher w(source);
    ASSERT_EQ(::raise(SIGINT), 0);
    sigset_t pending;
    sigpending(&pending);
    EXPECT_TRUE(sigismember(&pending, SIGINT));  // blocked in this thread: held for the watcher
  }
  // Still alive: the signal was taken, and said so.
  EXPECT_TRUE(source.token().requested());
  EXPECT_EQ(source.token().reason(), "SIGINT received");
  sigset_t pending;
  sigpending(&pending);
  EXPECT_FALSE(sigismember(&pending, SIGINT));
}

// Ctrl-\ (SIGQUIT) is an abort like the others: its default action (a core dump) ended a move
// with no halt.
TEST(SignalWatcher, SigquitIsTakenAsAnAbort) {
  CancelSource source;
  {
    SignalWatcher w(source);
    ASSERT_EQ(::raise(SIGQUIT), 0);
  }
  EXPECT_TRUE(source.token().requested());
  EXPECT_EQ(source.token().reason(), "SIGQUIT received");
  // Started with it ignored, as a shell without job control starts its background jobs (SIGINT
  // and SIGQUIT both): taken as SIGINT is (`kill -QUIT` left `rig plant serve &` running: a review).
  struct sigaction ignore {}, was {};
  ignore.sa_handler = SIG_IGN;
  ASSERT_EQ(::sigaction(SIGQUIT, &ignore, &was), 0);
  CancelSource again;
  {
    SignalWatcher w(again);
    ASSERT_EQ(::raise(SIGQUIT), 0);
  }
  ::sigaction(SIGQUIT, &was, nullptr);
  EXPECT_TRUE(again.token().requested());
  EXPECT_EQ(again.token().reason(), "SIGQUIT received");
}

// A signal to the process while two watchers live (one command's, one of a helper it runs): one
// of them takes it, and neither is left blocked in a read of a signal the other took.
TEST(SignalWatcher, TwoWatchersTakeOneProcessSignalOnceAndBothEnd) {
  CancelSource a, b;
  {
    SignalWatcher wa(a);
    SignalWatcher wb(b);
    ASSERT_EQ(::kill(::getpid(), SIGTERM), 0);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (!a.token().requested() && !b.token().requested() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_NE(a.token().requested(), b.token().requested());
  EXPECT_EQ((a.token().requested() ? a : b).token().reason(), "SIGTERM received");
}

}  // namespace
}  // namespace rig
