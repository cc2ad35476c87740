// Stop signals: SIGINT / SIGTERM set the flag a long run polls; the exit code is 128 + signal;
// the first signal restores the default action, so a second one ends a run that does not stop.
#include "ehc_common/stop_signal.h"

#include <gtest/gtest.h>

#include <csignal>

TEST(StopSignal, SignalsSetTheFlagAndTheExitCode) {
  ehc_common::requestStop(0);
  ehc_common::installStopSignals();
  EXPECT_FALSE(ehc_common::stopRequested());
  EXPECT_EQ(ehc_common::stopExitCode(), 0);
  std::raise(SIGTERM);
  EXPECT_TRUE(ehc_common::stopRequested());
  EXPECT_EQ(ehc_common::stopSignal(), SIGTERM);
  EXPECT_EQ(ehc_common::stopExitCode(), 143);
  // The handler is gone: a second signal would act as usual.
  struct sigaction now {};
  sigaction(SIGINT, nullptr, &now);
  EXPECT_EQ(now.sa_handler, SIG_DFL);
  ehc_common::requestStop(0);
  ehc_common::installStopSignals();
  std::raise(SIGINT);
  EXPECT_EQ(ehc_common::stopExitCode(), 130);
  ehc_common::requestStop(0);
  EXPECT_FALSE(ehc_common::stopRequested());
}
