// prepareOutputDir: creates the folder and proves a file can be written there before any work;
// otherwise a clear error naming the folder.
#include "ehc_common/output_dir.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <sys/stat.h>
#include <unistd.h>

using ehc_test::errorOf;

TEST(OutputDir, CreatesNestedFoldersAndLeavesNothingBehind) {
  const std::string root = ::testing::TempDir() + "/ehc_output_dir_" + std::to_string(::getpid());
  std::filesystem::remove_all(root);
  ehc_common::prepareOutputDir(root + "/a/b");
  EXPECT_TRUE(std::filesystem::is_directory(root + "/a/b"));
  EXPECT_TRUE(std::filesystem::is_empty(root + "/a/b"));
  ehc_common::prepareOutputDir(root + "/a/b");  // existing: fine
  std::filesystem::remove_all(root);
}

TEST(OutputDir, UnwritableFoldersAreClearErrors) {
  const std::string root = ::testing::TempDir() + "/ehc_output_dir_bad_" + std::to_string(::getpid());
  std::filesystem::remove_all(root);
  std::filesystem::create_directories(root);
  std::ofstream(root + "/file") << "x";
  std::string e = errorOf([&] { ehc_common::prepareOutputDir(root + "/file"); });
  EXPECT_NE(e.find("[OutputDir] cannot write to '" + root + "/file'"), std::string::npos) << e;
  e = errorOf([&] { ehc_common::prepareOutputDir(root + "/file/sub"); });
  EXPECT_NE(e.find("cannot write to '" + root + "/file/sub'"), std::string::npos) << e;
  e = errorOf([&] { ehc_common::prepareOutputDir(""); });
  EXPECT_NE(e.find("no folder given"), std::string::npos) << e;
  if (::geteuid() != 0) {  // root writes anywhere
    ::mkdir((root + "/ro").c_str(), 0555);
    e = errorOf([&] { ehc_common::prepareOutputDir(root + "/ro"); });
    EXPECT_NE(e.find("cannot write to '" + root + "/ro'"), std::string::npos) << e;
  }
  e = errorOf([&] { ehc_common::prepareOutputDir("/proc/ehc_output_dir"); });
  EXPECT_NE(e.find("cannot write to '/proc/ehc_output_dir'"), std::string::npos) << e;
  std::filesystem::remove_all(root);
}
