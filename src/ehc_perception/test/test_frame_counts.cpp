// FrameCounts: what became of a perception node's frames, per reason, and when the node logs
// the counts (a drop, or the first frame over the budget; at most every period; quiet while
// frames are only processed or rate-limited). Times are plain numbers: nothing is timed.
#include "ehc_perception/frame_counts.h"

#include <gtest/gtest.h>

using namespace ehc_perception;

TEST(FrameCounts, CountsPerReasonAndASummaryWithoutZeros) {
  FrameCounts c("clouds");
  EXPECT_EQ(c.summary(), "clouds: 0 processed");
  for (int i = 0; i < 3; ++i) c.add(FrameOutcome::Processed);
  c.countSubsampled();
  c.add(FrameOutcome::RateLimited);
  c.add(FrameOutcome::Stale);
  c.add(FrameOutcome::Stale);
  c.add(FrameOutcome::NoCameraPose);
  EXPECT_EQ(c.count(FrameOutcome::Processed), 3);
  EXPECT_EQ(c.count(FrameOutcome::Stale), 2);
  EXPECT_EQ(c.dropped(), 3) << "rate-limited frames are skipped by design, not dropped";
  EXPECT_EQ(c.summary(), "clouds: 3 processed (1 over the point budget, subsampled), 1 rate_limited, 2 stale, "
                         "1 no_camera_pose");
  EXPECT_EQ(toString(FrameOutcome::Superseded), "superseded");
  EXPECT_EQ(toString(FrameOutcome::Oversized), "oversized");
  EXPECT_EQ(toString(FrameOutcome::Malformed), "malformed");
  EXPECT_EQ(toString(FrameOutcome::Failed), "failed");
}

TEST(FrameCounts, TheLogLineComesWithDropsAtMostEveryPeriod) {
  FrameCounts c("images");
  for (int i = 0; i < 100; ++i) {
    c.add(FrameOutcome::Processed);
    c.add(FrameOutcome::RateLimited);
    EXPECT_EQ(c.reportDue(i * 0.1), "") << "nothing dropped: quiet";
  }
  c.add(FrameOutcome::Oversized);
  EXPECT_EQ(c.reportDue(10.0), "images: 100 processed, 100 rate_limited, 1 oversized");
  c.add(FrameOutcome::Oversized);
  EXPECT_EQ(c.reportDue(15.0), "") << "within the period";
  EXPECT_EQ(c.reportDue(20.0, 10.0), "images: 100 processed, 100 rate_limited, 2 oversized") << "held until then";
  EXPECT_EQ(c.reportDue(40.0), "") << "nothing new";
  // Subsampling: the first frame over the budget is reported, not every one after it.
  FrameCounts s("clouds");
  s.add(FrameOutcome::Processed);
  s.countSubsampled();
  EXPECT_NE(s.reportDue(0.0), "");
  for (int i = 1; i < 10; ++i) {
    s.add(FrameOutcome::Processed);
    s.countSubsampled();
    EXPECT_EQ(s.reportDue(20.0 * i), "");
  }
}
