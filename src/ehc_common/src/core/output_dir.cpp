#include "ehc_common/output_dir.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <unistd.h>

namespace ehc_common {

void prepareOutputDir(const std::string& dir) {
  namespace fs = std::filesystem;
  auto fail = [&](const std::string& why) {
    throw std::invalid_argument("[OutputDir] cannot write to '" + dir + "': " + why);
  };
  if (dir.empty()) fail("no folder given");
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) fail(ec.message());
  if (!fs::is_directory(dir, ec)) fail("not a folder");
  const std::string probe = dir + "/.write_test_" + std::to_string(::getpid());
  errno = 0;
  {
    std::ofstream f(probe);
    if (!(f << "probe" << std::flush)) fail(errno ? std::strerror(errno) : "the test file cannot be written");
  }
  std::remove(probe.c_str());
}

}  // namespace ehc_common
