// scripts/demo.sh at script level, with stub ROS commands (no master, no nodes; a few seconds):
// the stubs stand in for rosmaster / rosrun / rosparam through a stub devel space (EHC_DEVEL)
// whose setup.bash puts them first on PATH; the stub sequencer writes the summary where the
// script tells it to.
//   - An absolute OUT= wrote inside the repository ("$WS//abs/path") and
//     exited 2 ("no summary written") after a completed run.
//   - Each node's private namespace is deleted before it starts (parameters
//     of an earlier run on the same master never leak into this one).

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

namespace {
const std::string kWorkspace = std::string(EHC_CONFIG_DIR) + "/..";

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeExecutable(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  ::chmod(path.c_str(), 0755);
}

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

/// A stub devel space in a fresh temporary folder; returns the folder.
std::string makeStubs() {
  char tmpl[] = "/tmp/ehc_demo_script_XXXXXX";
  const std::string dir = ::mkdtemp(tmpl);
  ::mkdir((dir + "/devel").c_str(), 0755);
  ::mkdir((dir + "/bin").c_str(), 0755);
  std::ofstream(dir + "/devel/setup.bash") << "export PATH=\"" << dir << "/bin:$PATH\"\n";
  writeExecutable(dir + "/bin/rosmaster", "#!/bin/bash\nexec sleep 600\n");
  // rosparam: an earlier run left /ehc_controller_node/mode behind on this master.
  writeExecutable(dir + "/bin/rosparam",
                  "#!/bin/bash\necho \"rosparam $*\" >> " + dir + "/calls.log\n"
                  "case \"$1\" in\n"
                  "  get) echo true ;;\n"
                  "  list) [ \"$2\" = /ehc_controller_node ] && echo /ehc_controller_node/mode ;;\n"
                  "esac\nexit 0\n");
  // rosrun: the sequencer writes its summary and trace and ends the run; other nodes idle.
  writeExecutable(dir + "/bin/rosrun",
                  "#!/bin/bash\necho \"rosrun $*\" >> " + dir + "/calls.log\n"
                  "case \" $* \" in\n"
                  "  *' ehc_grasp_sequencer_node '*)\n"
                  "    for a in \"$@\"; do\n"
                  "      case \"$a\" in _summary:=*) summary=\"${a#*:=}\" ;; _trace:=*) trace=\"${a#*:=}\" ;; esac\n"
                  "    done\n"
                  "    echo '{\"objects\": [{\"name\": \"front\", \"success\": true, \"time_s\": 1.0, "
                  "\"tfm\": 1.0, \"approach\": \"tag\", \"grasp_from_candidate\": false}], "
                  "\"successes\": 1, \"objects_total\": 1, \"total_time_s\": 1.0, \"mode\": \"ehc\"}' > \"$summary\"\n"
                  "    echo t,object > \"$trace\"\n"
                  "    echo '[grasp] stub sequencer done'\n"
                  "    exit 0 ;;\n"
                  "esac\nexec sleep 600\n");
  return dir;
}

int runDemo(const std::string& env, std::string* output) {
  const std::string cmd = "cd / && " + env + " EHC_DEMO_PORT=1 TAG_OBJECTS=front WALL_LIMIT=60 bash " +
                          kWorkspace + "/src/ehc_bringup/scripts/demo.sh 2>&1";
  FILE* p = ::popen(cmd.c_str(), "r");
  std::array<char, 512> buf{};
  while (std::fgets(buf.data(), buf.size(), p)) *output += buf.data();
  return WEXITSTATUS(::pclose(p));
}
}  // namespace

TEST(DemoScript, AbsoluteOutFolderIsUsedAsGiven) {
  const std::string dir = makeStubs();
  const std::string out = dir + "/out";
  std::string log;
  const int rc = runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + out, &log);
  EXPECT_EQ(rc, 0) << log;
  EXPECT_TRUE(exists(out + "/summary.json")) << log;
  EXPECT_TRUE(exists(out + "/logs/sequencer.log")) << log;
  EXPECT_FALSE(exists(kWorkspace + dir)) << "demo.sh wrote inside the repository: " << kWorkspace + dir;
  EXPECT_NE(slurp(dir + "/calls.log").find("_summary:=" + out + "/summary.json"), std::string::npos)
      << slurp(dir + "/calls.log");
}

TEST(DemoScript, RelativeOutFolderIsInsideTheWorkspace) {
  const std::string dir = makeStubs();
  const std::string rel = "build/test_demo_script_out";
  std::string log;
  const int rc = runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + rel, &log);
  EXPECT_EQ(rc, 0) << log;
  EXPECT_TRUE(exists(kWorkspace + "/" + rel + "/summary.json")) << log;
}

TEST(DemoScript, EveryNodesPrivateParametersAreDeletedBeforeItStarts) {
  const std::string dir = makeStubs();
  std::string log;
  ASSERT_EQ(runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + dir + "/out", &log), 0) << log;
  const std::string calls = slurp(dir + "/calls.log");
  const auto deleted = calls.find("rosparam delete /ehc_controller_node\n");
  EXPECT_NE(deleted, std::string::npos) << calls;
  for (const char* ns : {"/ehc_sim_node", "/ehc_tag_front", "/ehc_grasp_node", "/ehc_obstacle_node",
                         "/ehc_controller_node", "/ehc_grasp_sequencer_node"})
    EXPECT_NE(calls.find(std::string("rosparam list ") + ns + "\n"), std::string::npos)
        << ns << "\n" << calls;
  const auto started = calls.find("rosrun ehc_control ehc_controller_node");
  ASSERT_NE(started, std::string::npos) << calls;
  EXPECT_LT(deleted, started) << "deleted before the controller starts:\n" << calls;
}
