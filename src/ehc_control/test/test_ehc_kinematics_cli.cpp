// ehc_kinematics CLI: JSON output for a valid call, exit code 2 + stderr for bad calls; --check
// prints one line per check and exits 0 on a shipped robot, 1 with a PROBLEM line on a broken copy.
// ehc_reachability CLI: unparsable values are start-up errors naming the flag.

#include "ehc_common/json.h"
#include "ehc_test/temp_dir.h"

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace {

struct Result {
  int code;
  std::string out;
};

// Per-process stderr file: concurrent test runs (CI jobs, parallel runs) must not read
// each other's output.
const std::string& stderrPath() {
  static const std::string path = "/tmp/ehc_kin_err_" + std::to_string(getpid()) + ".txt";
  return path;
}

Result run(const std::string& args, const std::string& bin = EHC_KINEMATICS_BIN) {
  const std::string cmd = bin + " " + args + " 2>" + stderrPath();
  FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  const int status = pclose(p);
  return {WEXITSTATUS(status), out};
}

const std::string kRobot =
    std::string("--robot ") + EHC_CONFIG_DIR + "/robots/realman_rm65_water2/robot.yaml";

}  // namespace

TEST(EhcKinematicsCli, PrintsOneJsonObject) {
  const Result r = run(kRobot + " --q 0,0.1,1.2,0,0.8,0 --base 1,2,0.5");
  ASSERT_EQ(r.code, 0);
  EXPECT_EQ(r.out.front(), '{');
  for (const char* key : {"\"joint_names\":[\"joint1\"", "\"base_type\":\"differential\"",
                          "\"T\":[[", "\"J\":[[", "\"manipulability\":"})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << " missing in " << r.out;
  // One JSON object: T is 4x4 with last row [0,0,0,1]; J has 6 rows of 8 columns.
  const ehc_common::Json j = ehc_common::Json::parse(r.out);
  ASSERT_EQ(j["T"].size(), 4u);
  EXPECT_EQ(j["T"][3], ehc_common::Json::parse("[0,0,0,1]"));
  ASSERT_EQ(j["J"].size(), 6u);
  for (const auto& row : j["J"]) EXPECT_EQ(row.size(), 8u);
  EXPECT_EQ(j["joint_names"].size(), 6u);
  EXPECT_GT(j["manipulability"].get<double>(), 0.0);
}

TEST(EhcKinematicsCli, OtherLink) {
  const Result r = run(kRobot + " --q ready --link camera_color_optical_frame");
  ASSERT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("\"link\":\"camera_color_optical_frame\""), std::string::npos);
}

TEST(EhcKinematicsCli, ErrorsExitWithCode2) {
  EXPECT_EQ(run(kRobot + " --q 0,0,0").code, 2);                    // wrong joint count
  EXPECT_EQ(run(kRobot + " --q 0,0,0,0,0,x").code, 2);              // not a number
  EXPECT_EQ(run(kRobot + " --q ready --link nowhere").code, 2);     // unknown link
  EXPECT_EQ(run("--robot /nonexistent.yaml --q ready").code, 2);    // unreadable config
  EXPECT_EQ(run("--q ready").code, 2);                              // missing --robot
  EXPECT_EQ(run(kRobot + " --q ready --base 0,0").code, 2);         // bad base
  EXPECT_EQ(run(kRobot + " --q nan,0,0,0,0,0").code, 2);            // NaN
  EXPECT_EQ(run(kRobot + " --q ready --bogus").code, 2);            // unknown flag
}

std::string lastStderr() {
  std::ifstream in(stderrPath());
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(EhcKinematicsCli, UnparsableValuesNameTheFlag) {
  EXPECT_EQ(run(kRobot + " --q ready --base 0,0,0x").code, 2);
  EXPECT_NE(lastStderr().find("--base: '0x' is not a number"), std::string::npos) << lastStderr();
  EXPECT_EQ(run(kRobot + " --q ready --q ready").code, 2);
  EXPECT_NE(lastStderr().find("--q: given twice"), std::string::npos) << lastStderr();
}

TEST(EhcKinematicsCli, CheckPrintsOneOkLinePerCheckAndExits0) {
  const Result r = run("--robot realman_rm65_water2 --check");
  EXPECT_EQ(r.code, 0) << r.out;
  std::istringstream lines(r.out);
  int n = 0;
  for (std::string line; std::getline(lines, line); ++n) EXPECT_EQ(line.rfind("ok ", 0), 0u) << line;
  EXPECT_EQ(n, 9) << r.out;
  EXPECT_NE(r.out.find("ok camera view:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ok fingers: the pads touch at the TCP when closed"), std::string::npos) << r.out;
}

TEST(EhcKinematicsCli, CheckExits1WithOneLinePerProblem) {
  ehc_test::TempDir dir("ehc_kin_check");
  ehc_test::copyFolder(std::string(EHC_CONFIG_DIR) + "/robots/kuka_iiwa14_kmr", dir.path + "/kuka");
  // The ready pose turned to the right: the hand camera looks away from the table.
  ehc_test::replaceInFile(dir.path + "/kuka/robot.yaml", "ready:    [0.0,", "ready:    [-1.5,");
  const Result r = run("--robot " + dir.path + "/kuka/robot.yaml --check");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("\nPROBLEM camera view: in the ready pose the camera"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ok reachability map:"), std::string::npos) << r.out;
  // Another view region, where the camera looks now: nothing wrong.
  EXPECT_EQ(run("--robot " + dir.path + "/kuka/robot.yaml --check --view-region 0.2,0.6,-1.8,-1.5,0.75,0.85").code, 0);
  EXPECT_EQ(run(kRobot + " --check --view-region 1,2").code, 2);  // six values
  EXPECT_NE(lastStderr().find("--view-region needs 6 values"), std::string::npos) << lastStderr();
}

// A loose parser read `--samples 1e6` as one sample, wrote a one-voxel map and exited 0.
TEST(EhcReachabilityCli, UnparsableValuesAreStartUpErrorsNamingTheFlag) {
  const std::string map = "/tmp/ehc_cli_map_" + std::to_string(getpid()) + ".bin";
  const std::string out = " --out " + map;
  std::remove(map.c_str());
  for (const std::string& bad : {std::string("--samples 1e6"), std::string("--samples 10k"),
                                 std::string("--samples -5"), std::string("--seed 1.5"),
                                 std::string("--resolution 5cm"), std::string("--direction-bins x")}) {
    const std::string args = kRobot + out + (bad.rfind("--samples", 0) == 0 ? "" : " --samples 10") +
                             " " + bad;
    EXPECT_EQ(run(args, EHC_REACHABILITY_BIN).code, 2) << bad;
    const std::string flag = bad.substr(0, bad.find(' '));
    EXPECT_NE(lastStderr().find(flag + ":"), std::string::npos) << bad << ": " << lastStderr();
  }
  EXPECT_FALSE(std::ifstream(map).good()) << "no map written";
  EXPECT_EQ(run(kRobot + out, EHC_REACHABILITY_BIN).code, 2);
  EXPECT_NE(lastStderr().find("--samples: is required"), std::string::npos) << lastStderr();
  std::remove(stderrPath().c_str());
}
