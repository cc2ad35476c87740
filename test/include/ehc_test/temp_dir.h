#pragma once
// Generic test helpers of every package: a fresh temporary folder removed with its contents at
// the end of the scope, the file edits that make broken copies of a config folder, and the seed
// of a randomized test.

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include <stdlib.h>

namespace ehc_test {

/// A new folder /tmp/<prefix>_XXXXXX (unique per process and call), removed on destruction.
struct TempDir {
  explicit TempDir(const std::string& prefix = "ehc_test") {
    std::string tmpl = "/tmp/" + prefix + "_XXXXXX";
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed for " + tmpl);
    path = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path;
};

inline std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Replaces the first occurrence of `from` in the file by `to`; throws when `from` is not there
/// (a test that edits nothing would prove nothing).
inline void replaceInFile(const std::string& path, const std::string& from, const std::string& to) {
  std::string text = readText(path);
  const auto at = text.find(from);
  if (at == std::string::npos) throw std::runtime_error("'" + from + "' is not in " + path);
  text.replace(at, from.size(), to);
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
}

/// Copies the folder `from` (its files, recursively) to the new folder `to`.
inline void copyFolder(const std::string& from, const std::string& to) {
  std::filesystem::copy(from, to, std::filesystem::copy_options::recursive);
}

/// The seed of a randomized test: EHC_TEST_SEED if set (reruns a printed seed), else a fresh
/// one; printed with `who`.
inline unsigned testSeed(const std::string& who) {
  const char* given = std::getenv("EHC_TEST_SEED");
  const unsigned seed = given ? static_cast<unsigned>(std::stoul(given)) : std::random_device{}();
  std::cout << "[" << who << "] seed " << seed << " (EHC_TEST_SEED=" << seed << " reruns it)" << std::endl;
  return seed;
}

}  // namespace ehc_test
