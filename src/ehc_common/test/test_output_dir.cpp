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

TEST(OutputDir, AnOutputFileIsCheckedWithoutTouchingAnExistingOne) {
  const std::string root = ::testing::TempDir() + "/ehc_output_file_" + std::to_string(::getpid());
  std::filesystem::remove_all(root);
  ehc_common::prepareOutputFile(root + "/sub/map.bin");
  EXPECT_TRUE(std::filesystem::is_directory(root + "/sub"));
  EXPECT_FALSE(std::filesystem::exists(root + "/sub/map.bin"));
  std::ofstream(root + "/sub/keep.bin") << "data";
  ehc_common::prepareOutputFile(root + "/sub/keep.bin");
  std::ifstream in(root + "/sub/keep.bin");
  std::string text;
  in >> text;
  EXPECT_EQ(text, "data");
  std::string e = errorOf([&] { ehc_common::prepareOutputFile(root + "/sub"); });
  EXPECT_NE(e.find("cannot write to '" + root + "/sub': a folder"), std::string::npos) << e;
  e = errorOf([&] { ehc_common::prepareOutputFile(root + "/sub/keep.bin/x"); });
  EXPECT_NE(e.find("cannot write to '" + root + "/sub/keep.bin"), std::string::npos) << e;
  e = errorOf([&] { ehc_common::prepareOutputFile("/proc/ehc_map.bin"); });
  EXPECT_NE(e.find("cannot write to '/proc/ehc_map.bin'"), std::string::npos) << e;
  std::filesystem::remove_all(root);
}
