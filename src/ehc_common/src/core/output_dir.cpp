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

void prepareOutputFile(const std::string& file) {
  namespace fs = std::filesystem;
  if (file.empty() || file.back() == '/') throw std::invalid_argument("[OutputDir] cannot write to '" + file + "': no file name");
  const fs::path parent = fs::path(file).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (ec) throw std::invalid_argument("[OutputDir] cannot write to '" + file + "': " + ec.message());
  if (fs::is_directory(file, ec)) throw std::invalid_argument("[OutputDir] cannot write to '" + file + "': a folder");
  const bool existed = fs::exists(file, ec);
  errno = 0;
  {
    std::ofstream f(file, std::ios::app);
    if (!f) throw std::invalid_argument("[OutputDir] cannot write to '" + file + "': " +
                                        (errno ? std::strerror(errno) : "cannot be opened"));
  }
  if (!existed) std::remove(file.c_str());
}

}  // namespace ehc_common
