// scripts/demo.sh at script level, with stub ROS commands (no master, no nodes; a few seconds):
// the stubs stand in for rosmaster / rosrun / rosparam through a stub devel space (EHC_DEVEL)
// whose setup.bash puts them first on PATH; the stub sequencer writes the summary where the
// script tells it to.
//   - An absolute OUT= wrote inside the repository ("$WS//abs/path") and
//     exited 2 ("no summary written") after a completed run.
//   - Each node's private namespace is deleted before it starts (parameters
//     of an earlier run on the same master never leak into this one).
//   - A bad EHC_DEMO_PORT or an OUT that cannot be written is named (it was blamed on "another
//     master").
//   - When a node dies, the others get SIGINT and the master SIGTERM once they are gone (the
//     master got SIGINT with them and could take until the SIGKILL 5 s later to exit).

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
  const std::string cmd = "cd / && EHC_DEMO_PORT=1 TAG_OBJECTS=front WALL_LIMIT=60 " + env + " bash " +
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

TEST(DemoScript, ABadPortOrAnUnwritableOutIsNamed) {
  const std::string dir = makeStubs();
  std::string log;
  EXPECT_EQ(runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + dir + "/out EHC_DEMO_PORT=abc", &log), 2);
  EXPECT_NE(log.find("EHC_DEMO_PORT must be a TCP port number 1-65535 (got 'abc')"), std::string::npos) << log;
  log.clear();
  EXPECT_EQ(runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + dir + "/out EHC_DEMO_PORT=70000", &log), 2);
  EXPECT_NE(log.find("got '70000'"), std::string::npos) << log;
  log.clear();
  std::ofstream(dir + "/a_file") << "x";
  EXPECT_EQ(runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + dir + "/a_file/out", &log), 2);
  EXPECT_NE(log.find("cannot write to the output folder OUT=" + dir + "/a_file/out"), std::string::npos) << log;
  EXPECT_EQ(log.find("another master"), std::string::npos) << log;
}

TEST(DemoScript, WhenANodeDiesTheNodesGetSigintAndTheMasterSigtermAfterThem) {
  const std::string dir = makeStubs();
  // Stubs that log the signal they get (python: a background child of a script starts with
  // SIGINT ignored, which bash cannot trap; the real nodes install their own handler too).
  const std::string stub = "#!/usr/bin/python3\nimport signal, sys, time\nname = sys.argv[1]\n"
                           "def on(sig, _):\n    open('" + dir + "/signals.log', 'a').write('%s %s\\n' % (name, signal.Signals(sig).name))\n"
                           "    sys.exit(0) if sig != signal.SIGINT or name != 'master' else None\n"
                           "signal.signal(signal.SIGINT, on)\nsignal.signal(signal.SIGTERM, on)\n"
                           "if name == 'ehc_controller_node':\n    time.sleep(1.0)\n    sys.exit(1)\n"
                           "while True:\n    time.sleep(0.05)\n";
  writeExecutable(dir + "/bin/stub_process", stub);
  writeExecutable(dir + "/bin/rosmaster", "#!/bin/bash\nexec " + dir + "/bin/stub_process master\n");
  writeExecutable(dir + "/bin/rosrun", "#!/bin/bash\nexec " + dir + "/bin/stub_process \"$2\"\n");
  std::string log;
  EXPECT_EQ(runDemo("EHC_DEVEL=" + dir + "/devel OUT=" + dir + "/out", &log), 2);
  EXPECT_NE(log.find("demo.sh: controller exited unexpectedly"), std::string::npos) << log;
  const std::string signals = slurp(dir + "/signals.log");
  for (const char* node : {"ehc_sim_node", "ehc_tag_node", "ehc_grasp_node", "ehc_obstacle_node", "ehc_grasp_sequencer_node"})
    EXPECT_NE(signals.find(std::string(node) + " SIGINT\n"), std::string::npos) << node << "\n" << signals;
  const auto master = signals.find("master SIGTERM\n");
  ASSERT_NE(master, std::string::npos) << "the master was not stopped with SIGTERM:\n" << signals;
  EXPECT_EQ(signals.find("master SIGINT"), std::string::npos) << signals;
  EXPECT_EQ(signals.rfind("SIGINT"), signals.rfind("SIGINT", master)) << "nodes after the master:\n" << signals;
}
