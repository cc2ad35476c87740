// CommandLine: the one strict parser of the command-line tools. Every unparsable value, unknown
// flag, repeated flag or missing value is an error naming the flag (a loose
// parser once read `ehc_reachability --samples 1e6` as one sample and exited 0). The tools' own tests
// (test_ehc_tools_cli, test_perception_cli, test_experiment_cli) run the binaries.

#include "ehc_common/command_line.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

using ehc_common::CommandLine;
using ehc_test::errorOf;

namespace {
CommandLine parse(std::vector<const char*> words) {
  words.insert(words.begin(), "tool");
  return CommandLine(static_cast<int>(words.size()), words.data(),
                     {"samples", "resolution", "base", "mode", "out"}, {"help", "summary"});
}

}  // namespace

TEST(CommandLine, ParsesOptionsSwitchesAndDefaults) {
  const auto cli = parse({"--samples", "1000000", "--resolution", "0.05", "--base", "1,2.5,-3",
                          "--summary", "-h", "--mode", "scene"});
  EXPECT_EQ(cli.integer("samples", 0, 1, 2000000000L), 1000000);
  EXPECT_DOUBLE_EQ(cli.real("resolution", 0.1), 0.05);
  EXPECT_TRUE(cli.vector3("base", Eigen::Vector3d::Zero()).isApprox(Eigen::Vector3d(1, 2.5, -3)));
  EXPECT_TRUE(cli.has("summary"));
  EXPECT_TRUE(cli.has("help"));
  EXPECT_EQ(cli.choice("mode", {"scene", "object"}, "object"), "scene");
  EXPECT_FALSE(cli.has("out"));
  EXPECT_EQ(cli.text("out", "fallback"), "fallback");
  const auto empty = parse({});
  EXPECT_EQ(empty.integer("samples", 7, 1, 10), 7);
  EXPECT_DOUBLE_EQ(empty.real("resolution", 0.1), 0.1);
}

TEST(CommandLine, UnparsableValuesNameTheFlag) {
  struct Case {
    std::vector<const char*> words;
    std::string flag;
  };
  const std::vector<Case> cases = {
      {{"--samples", "1e6"}, "--samples"},    {{"--samples", "10x"}, "--samples"},
      {{"--samples", ""}, "--samples"},       {{"--samples", " 5"}, "--samples"},
      {{"--samples", "0"}, "--samples"},      {{"--samples", "99999999999999999999"}, "--samples"},
      {{"--samples", "-3"}, "--samples"},     {{"--resolution", "abc"}, "--resolution"},
      {{"--resolution", "0.05m"}, "--resolution"}, {{"--resolution", "nan"}, "--resolution"},
      {{"--resolution", "inf"}, "--resolution"},   {{"--resolution", "1e999"}, "--resolution"},
      {{"--base", "0,0"}, "--base"},          {{"--base", "0,,0"}, "--base"},
      {{"--base", "0,0,0,"}, "--base"},       {{"--mode", "Scene"}, "--mode"},
  };
  for (const auto& c : cases) {
    const std::string what = errorOf([&] {
      const auto cli = parse(c.words);
      cli.integer("samples", 1, 1, 2000000000L);
      cli.real("resolution", 0.1);
      cli.vector3("base", Eigen::Vector3d::Zero());
      cli.choice("mode", {"scene", "object"}, "scene");
    });
    EXPECT_NE(what.find("[CommandLine] " + c.flag + ":"), std::string::npos)
        << c.words[0] << " " << c.words[1] << " -> '" << what << "'";
  }
}

TEST(CommandLine, UnknownRepeatedAndIncompleteFlagsAreErrors) {
  EXPECT_NE(errorOf([] { parse({"--sample", "5"}); }).find("--sample: unknown flag"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parse({"--samples", "5", "--samples", "6"}); }).find("given twice"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parse({"--samples"}); }).find("--samples: needs a value"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parse({"samples"}); }).find("unexpected argument 'samples'"),
            std::string::npos);
  EXPECT_NE(errorOf([] { parse({}).text("out"); }).find("--out: is required"), std::string::npos);
}

TEST(CommandLine, FirstWordCanBeACommand) {
  const std::vector<const char*> argv = {"tool", "reach", "--samples", "3"};
  const CommandLine cli(4, argv.data(), {"samples"}, {}, /*first=*/2);
  EXPECT_EQ(cli.integer("samples", 0, 1, 10), 3);
}
