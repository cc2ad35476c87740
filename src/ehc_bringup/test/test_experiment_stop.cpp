// ehc_experiment: --out is checked before any work (an unwritable folder fails at once, not after
// the run), and SIGTERM / SIGINT end a run with the results of what was completed, marked partial
// in summary.json, and the exit code 143 / 130.

#include "ehc_common/json.h"

#include <gtest/gtest.h>

#include <csignal>
#include <fcntl.h>
#include <filesystem>
#include <functional>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace {

const std::string kRobot = std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml";

/// ehc_experiment with `args`, its stderr + stdout read line by line; `on_line` may signal it.
struct Outcome {
  int code = -1;
  std::string out;
};
Outcome run(const std::vector<std::string>& args, const std::function<void(pid_t, const std::string&)>& on_line = nullptr) {
  int fds[2];
  if (::pipe(fds) != 0) return {};
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::dup2(fds[1], 1);
    ::dup2(fds[1], 2);
    ::close(fds[0]);
    std::vector<char*> argv{const_cast<char*>(EHC_EXPERIMENT_BIN)};
    for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    ::execv(EHC_EXPERIMENT_BIN, argv.data());
    ::_exit(127);
  }
  ::close(fds[1]);
  Outcome r;
  std::string line;
  char c;
  while (::read(fds[0], &c, 1) == 1) {
    r.out += c;
    if (c != '\n') {
      line += c;
      continue;
    }
    if (on_line) on_line(pid, line);
    line.clear();
  }
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

ehc_common::Json readJson(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ehc_common::Json::parse(ss.str());
}

std::string freshDir(const std::string& name) {
  const std::string dir = ::testing::TempDir() + "/" + name + "_" + std::to_string(::getpid());
  std::filesystem::remove_all(dir);
  return dir;
}

}  // namespace

TEST(ExperimentStop, AnUnwritableOutFailsBeforeAnyWork) {
  // A file in the way, and /proc (not writable even by root). Before: grasp and poses ran the
  // whole experiment (5.7 s and 25.7 s of work), then failed writing.
  const std::string dir = freshDir("ehc_stop_out");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/file") << "x";
  const std::vector<std::vector<std::string>> cmds = {
      {"grasp", "--method", "ehc", "--sets", "1", "--out", dir + "/file"},
      {"poses", "--method", "ehc", "--sets", "1", "--per-set", "1", "--out", "/proc/ehc_experiment_out"},
      {"reach", "--robot", kRobot, "--sets", "1", "--points", "2", "--out", dir + "/file/sub"}};
  for (const std::vector<std::string>& args : cmds) {
    const Outcome r = run(args);
    EXPECT_EQ(r.code, 2) << args[0] << ": " << r.out;
    EXPECT_NE(r.out.find("[OutputDir] cannot write to '" + args.back() + "'"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("ETA"), std::string::npos) << args[0] << ": work began before the check\n" << r.out;
  }
  std::filesystem::remove_all(dir);
}

TEST(ExperimentStop, SigtermAfterTheFirstTargetsWritesThemMarkedPartial) {
  const std::string out = freshDir("ehc_stop_reach");
  bool sent = false;
  const Outcome r = run({"reach", "--robot", kRobot, "--method", "all", "--sets", "2", "--points", "20", "--seed", "3",
                     "--out", out},
                    [&](pid_t pid, const std::string& line) {
                      if (!sent && line.find(" targets ") != std::string::npos && line.find("ETA") != std::string::npos) {
                        ::kill(pid, SIGTERM);
                        sent = true;
                      }
                    });
  ASSERT_TRUE(sent) << r.out;
  EXPECT_EQ(r.code, 143) << r.out;
  EXPECT_NE(r.out.find("interrupted (signal 15)"), std::string::npos) << r.out;
  // One summary per method: the ones the signal cut short or never started say partial.
  const ehc_common::Json s = readJson(out + "/summary.json");
  ASSERT_TRUE(s.is_array()) << s.dump();
  ASSERT_EQ(s.size(), 3u);
  int targets = 0, partial = 0;
  for (const auto& m : s) {
    EXPECT_EQ(m["targets_planned"].get<int>(), 40);
    targets += m["targets"].get<int>();
    partial += m["partial"].get<bool>();
  }
  EXPECT_GE(targets, 1);
  EXPECT_LT(targets, 120);
  EXPECT_GE(partial, 1);
  EXPECT_TRUE(s[2]["partial"].get<bool>());
  std::ifstream trials(out + "/trials.csv");
  int rows = -1;  // the header
  for (std::string line; std::getline(trials, line);) ++rows;
  EXPECT_EQ(rows, targets);
  std::filesystem::remove_all(out);
}

TEST(ExperimentStop, SigintAfterTheFirstGraspRunWritesTheCompletedRunsMarkedPartial) {
  const std::string out = freshDir("ehc_stop_poses");
  bool sent = false;
  const Outcome r = run({"poses", "--method", "ehc", "--sets", "1", "--per-set", "1", "--jobs", "1", "--out", out},
                    [&](pid_t pid, const std::string& line) {
                      if (!sent && line.find("1/3") != std::string::npos) {
                        ::kill(pid, SIGINT);
                        sent = true;
                      }
                    });
  ASSERT_TRUE(sent) << r.out;
  EXPECT_EQ(r.code, 130) << r.out;
  const ehc_common::Json s = readJson(out + "/summary.json");
  EXPECT_TRUE(s["partial"].get<bool>()) << s.dump();
  EXPECT_EQ(s["runs_planned"].get<int>(), 3);
  EXPECT_EQ(s["runs_done"].get<int>(), 1);
  ASSERT_EQ(s["methods"].size(), 1u);
  EXPECT_EQ(s["methods"][0]["grasps"].get<int>(), 1);
  std::ifstream table(out + "/table.md");
  std::stringstream text;
  text << table.rdbuf();
  EXPECT_NE(text.str().find("PARTIAL: interrupted"), std::string::npos) << text.str();
  std::filesystem::remove_all(out);
}
