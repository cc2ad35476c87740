#pragma once
// The output folder of a tool that writes result files (ehc_experiment --out): created and
// checked before any work, so a folder that cannot be written fails at once, not after a run.
// ROS-free.

#include <string>

namespace ehc_common {

/// Creates `dir` (and its parents) if needed and writes and removes a probe file in it. Throws
/// std::invalid_argument "[OutputDir] cannot write to '<dir>': <reason>" (an empty path, a
/// file in the way, no permission, a read-only file system).
void prepareOutputDir(const std::string& dir);

}  // namespace ehc_common
