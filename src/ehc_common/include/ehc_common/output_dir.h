#pragma once
// The output folder or file of a tool that writes results (ehc_experiment --out,
// ehc_reachability --out): created and checked before any work, so a place that cannot be
// written fails at once, not after a run. ROS-free.

#include <string>

namespace ehc_common {

/// Creates `dir` (and its parents) if needed and writes and removes a probe file in it. Throws
/// std::invalid_argument "[OutputDir] cannot write to '<dir>': <reason>" (an empty path, a
/// file in the way, no permission, a read-only file system).
void prepareOutputDir(const std::string& dir);
/// The folder of `file` as prepareOutputDir, and `file` itself openable for writing (an
/// existing file is left as it is). Throws std::invalid_argument "[OutputDir] cannot write ...".
void prepareOutputFile(const std::string& file);

}  // namespace ehc_common
