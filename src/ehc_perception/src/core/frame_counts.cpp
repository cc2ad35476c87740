#include "ehc_perception/frame_counts.h"

#include "ehc_common/enum_names.h"

namespace ehc_perception {

namespace {
constexpr ehc_common::EnumNames<FrameOutcome, 8> kFrameOutcomeNames = {{{FrameOutcome::Processed, "processed"},
                                                                        {FrameOutcome::RateLimited, "rate_limited"},
                                                                        {FrameOutcome::Stale, "stale"},
                                                                        {FrameOutcome::Superseded, "superseded"},
                                                                        {FrameOutcome::NoCameraPose, "no_camera_pose"},
                                                                        {FrameOutcome::Oversized, "oversized"},
                                                                        {FrameOutcome::Malformed, "malformed"},
                                                                        {FrameOutcome::Failed, "failed"}}};
}  // namespace

std::string toString(FrameOutcome o) { return ehc_common::enumName(kFrameOutcomeNames, o, "FrameCounts"); }

long FrameCounts::dropped() const {
  long n = 0;
  for (FrameOutcome o : ehc_common::enumValues(kFrameOutcomeNames))
    if (o != FrameOutcome::Processed && o != FrameOutcome::RateLimited) n += count(o);
  return n;
}

std::string FrameCounts::summary() const {
  std::string s = what_ + ": " + std::to_string(count(FrameOutcome::Processed)) + " processed";
  if (subsampled_ > 0) s += " (" + std::to_string(subsampled_) + " over the point budget, subsampled)";
  for (FrameOutcome o : ehc_common::enumValues(kFrameOutcomeNames))
    if (o != FrameOutcome::Processed && count(o) > 0) s += ", " + std::to_string(count(o)) + " " + toString(o);
  return s;
}

std::string FrameCounts::reportDue(double now, double period) {
  // Drops, and the first frame over the budget (a camera whose every frame is: not every 10 s).
  const long events = dropped() + (subsampled_ > 0 ? 1 : 0);
  if (events == reported_ || now - reported_at_ < period) return "";
  reported_ = events;
  reported_at_ = now;
  return summary();
}

}  // namespace ehc_perception
