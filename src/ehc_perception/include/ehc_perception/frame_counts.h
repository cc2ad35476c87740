#pragma once
// FrameCounts: what became of the frames (depth clouds, images) a perception node received, one
// count per outcome, for the node's log. A node processes the newest frame only (its
// subscription keeps one: an older frame that arrives while the node is busy is replaced by a
// newer one before the node sees it), drops one that waited too long in the node (stale), and
// reads at most its point or pixel budget of the one it processes. ROS-free.

#include <array>
#include <string>
#include <utility>

namespace ehc_perception {

enum class FrameOutcome {
  Processed,     ///< used; what the node made of it was published
  RateLimited,   ///< skipped: inside the node's rate limit (by design, not a drop)
  Stale,         ///< waited in the node longer than its stale_after
  Superseded,    ///< replaced by a newer frame before it was used up (obstacle node: ray casting)
  NoCameraPose,  ///< no camera pose at its stamp within the wait
  Oversized,     ///< over the node's pixel budget (images)
  Malformed,     ///< a layout, size or encoding the node cannot read
  Failed,        ///< the core threw while processing it
};
std::string toString(FrameOutcome o);

/// Seconds between two log lines of the counts at most (FrameCounts::reportDue).
constexpr double kFrameReportPeriod = 10.0;

class FrameCounts {
 public:
  /// `what`: the frames' name in the summary ("clouds", "images").
  explicit FrameCounts(std::string what) : what_(std::move(what)) {}

  void add(FrameOutcome o) { ++counts_[static_cast<std::size_t>(o)]; }
  /// A processed frame that had more points than the budget (read subsampled).
  void countSubsampled() { ++subsampled_; }
  long count(FrameOutcome o) const { return counts_[static_cast<std::size_t>(o)]; }
  long subsampled() const { return subsampled_; }
  /// Frames dropped for any reason but the rate limit.
  long dropped() const;

  /// "clouds: 40 processed (3 over the point budget, subsampled), 120 rate_limited, 2 stale"
  /// (outcomes with a zero count left out).
  std::string summary() const;
  /// The summary when a frame was dropped since the last report, or the first frame was
  /// subsampled, and `now` is at least `period` s after the last report (the node's clock), else
  /// "": a log line that stays quiet while nothing is dropped.
  std::string reportDue(double now, double period = kFrameReportPeriod);

 private:
  std::string what_;
  std::array<long, 8> counts_{};
  long subsampled_ = 0;
  long reported_ = 0;  ///< the events (reportDue) at the last report
  double reported_at_ = -1e300;
};

}  // namespace ehc_perception
