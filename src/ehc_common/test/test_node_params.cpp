// NodeParams: typed, strict reads of a node's private parameters; unknown command-line
// parameters are errors; errors name the parameter.
#include "ehc_common/node_params.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

using ehc_common::NodeParams;
using ehc_common::ParamValue;
using ehc_test::errorOf;

namespace {
/// As rosrun sets `_name:=text` (roscpp: an int if it parses as one, else a double, else
/// true/false, else a string).
ParamValue asRosrun(const std::string& text) {
  try {
    std::size_t used = 0;
    const long i = std::stol(text, &used);
    if (used == text.size()) return ParamValue::ofInt(i);
  } catch (const std::exception&) {
  }
  try {
    std::size_t used = 0;
    const double d = std::stod(text, &used);
    if (used == text.size()) return ParamValue::ofDouble(d);
  } catch (const std::exception&) {
  }
  if (text == "true" || text == "True" || text == "TRUE") return ParamValue::ofBool(true);
  if (text == "false" || text == "False" || text == "FALSE") return ParamValue::ofBool(false);
  return ParamValue::ofString(text);
}

NodeParams params(const std::map<std::string, std::string>& cli, const std::map<std::string, ParamValue>& server = {}) {
  std::map<std::string, ParamValue> values = server;
  std::set<std::string> names;
  for (const auto& [k, v] : cli) {
    values[k] = asRosrun(v);
    names.insert(k);
  }
  return NodeParams("/test_node", values, names);
}
}  // namespace

TEST(NodeParams, TypedReadsAcceptTheirTypeAndFallBackWhenAbsent) {
  const NodeParams p = params({{"mpbs", "false"}, {"seed", "7"}, {"timeout", "1"}, {"rate", "0.5"}, {"mode", "tsmm"}});
  EXPECT_FALSE(p.get("mpbs", true));
  EXPECT_EQ(p.get<int>("seed", 1), 7);
  EXPECT_EQ(p.get<unsigned>("seed", 1u), 7u);
  EXPECT_EQ(p.get("timeout", 0.2), 1.0);  // an integer where a number is asked for
  EXPECT_EQ(p.get("rate", 0.0), 0.5);
  EXPECT_EQ(p.get<std::string>("mode", "ehc"), "tsmm");
  EXPECT_EQ(p.get<std::string>("absent", "x"), "x");
  EXPECT_EQ(p.getInRange("seed", 1, 0, 10), 7);
  EXPECT_NO_THROW(p.rejectUnknown());
  EXPECT_EQ(p.summary(), "_mode:=tsmm (command line), _mpbs:=false (command line), _rate:=0.5 (command line), "
                         "_seed:=7 (command line), _timeout:=1 (command line)");
}

TEST(NodeParams, AWrongTypeIsAnErrorNamingTheParameter) {
  // The values a user types by mistake: each names the parameter and the value.
  struct Case {
    std::string name, text, expected;
    std::function<void(const NodeParams&)> read;
  };
  const std::vector<Case> cases = {
      {"require_obstacles", "maybe", "'_require_obstacles' must be true or false (got text 'maybe')", [](const NodeParams& p) { p.get("require_obstacles", true); }},
      {"mpbs", "1", "'_mpbs' must be true or false (got an integer '1')", [](const NodeParams& p) { p.get("mpbs", true); }},
      {"free_run", "yes_please", "'_free_run' must be true or false", [](const NodeParams& p) { p.get("free_run", false); }},
      {"seed", "abc", "'_seed' must be an integer (got text 'abc')", [](const NodeParams& p) { p.get<unsigned>("seed", 1u); }},
      {"seed", "1.5", "'_seed' must be an integer (got a real number '1.5')", [](const NodeParams& p) { p.get<int>("seed", 1); }},
      {"seed", "-1", "'_seed' = -1 is outside [0, 4.29497e+09]", [](const NodeParams& p) { p.get<unsigned>("seed", 1u); }},
      {"port", "http", "'_port' must be an integer (got text 'http')", [](const NodeParams& p) { p.getInRange("port", 0, 0, 65535); }},
      {"port", "70000", "'_port' = 70000 is outside [0, 65535]", [](const NodeParams& p) { p.getInRange("port", 0, 0, 65535); }},
      {"target_timeout", "abc", "'_target_timeout' must be a finite number (got text 'abc')", [](const NodeParams& p) { p.get("target_timeout", 0.2); }},
      {"target_timeout", "nan", "'_target_timeout' must be a finite number", [](const NodeParams& p) { p.get("target_timeout", 0.2); }},
      {"mode", "1", "'_mode' must be text (got an integer '1')", [](const NodeParams& p) { p.get<std::string>("mode", ""); }},
  };
  for (const Case& c : cases) {
    const NodeParams p = params({{c.name, c.text}});
    const std::string e = errorOf([&] { c.read(p); });
    EXPECT_NE(e.find("[NodeParams] private parameter " + c.expected), std::string::npos) << c.name << ":=" << c.text << ": " << e;
  }
}

TEST(NodeParams, AnUnknownCommandLineParameterIsAnErrorAServerOneIsReported) {
  const NodeParams p = params({{"mdoe", "tsmm"}, {"config", "a.yaml"}}, {{"left_over", ParamValue::ofInt(3)}});
  p.get<std::string>("config", "");
  p.get<std::string>("mode", "");
  const std::string e = errorOf([&] { p.rejectUnknown(); });
  EXPECT_NE(e.find("[NodeParams] unknown private parameter '_mdoe' of /test_node (it reads _config, _mode)"), std::string::npos) << e;
  EXPECT_EQ(p.unread(), (std::vector<std::string>{"left_over", "mdoe"}));
  EXPECT_TRUE(p.fromCommandLine("mdoe"));
  EXPECT_FALSE(p.fromCommandLine("left_over"));
}

TEST(NodeParams, RequiredTextAndLists) {
  const NodeParams p = params({{"acks", "[a, b:cloud,c]"}, {"empty", ""}},
                              {{"list", [] {
                                  ParamValue l;
                                  l.kind = ParamValue::Kind::List;
                                  l.items = {ParamValue::ofString("x"), ParamValue::ofString("y")};
                                  return l;
                                }()}});
  EXPECT_EQ(p.getList("acks"), (std::vector<std::string>{"a", "b:cloud", "c"}));
  EXPECT_EQ(p.getList("list"), (std::vector<std::string>{"x", "y"}));
  EXPECT_TRUE(p.getList("empty").empty());
  EXPECT_TRUE(p.getList("absent").empty());
  const std::string e = errorOf([&] { p.requireText("config", "<controller.yaml>"); });
  EXPECT_NE(e.find("[NodeParams] missing private parameter _config:=<controller.yaml>"), std::string::npos) << e;
  EXPECT_EQ(ehc_common::splitNameList("[]"), std::vector<std::string>{});
  EXPECT_EQ(ehc_common::splitNameList("a b"), (std::vector<std::string>{"a", "b"}));
}

TEST(NodeParams, ValidateNamesTheOverridesThatWereRead) {
  const NodeParams p = params({{"target_timeout", "-1"}});
  const double t = p.get("target_timeout", 0.2);
  const std::string e = errorOf([&] {
    p.validate([&] {
      if (t < 0.0) throw std::invalid_argument("[SupervisorParams] parameter 'target_timeout' = -1 is outside [0.001, 60]");
    });
  });
  EXPECT_NE(e.find("outside [0.001, 60] (with the private parameters _target_timeout:=-1)"), std::string::npos) << e;
}

TEST(NodeParams, CommandLineNamesAreTheSingleUnderscoreAssignments) {
  const char* argv[] = {"node", "_config:=a.yaml", "__name:=x", "/topic:=/other", "_mode:=tsmm", "plain", "[_mode:=ehc"};
  EXPECT_EQ(ehc_common::commandLineParamNames(7, argv), (std::set<std::string>{"config", "mode"}));
}
