// ehc_experiment CLI: unparsable values, unknown and repeated flags are
// start-up errors naming the flag (exit code 2, nothing written).

#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <string>
#include <sys/wait.h>

namespace {
struct Result {
  int code;
  std::string out;
};
Result run(const std::string& args) {
  FILE* p = popen((std::string(EHC_EXPERIMENT_BIN) + " " + args + " 2>&1").c_str(), "r");
  std::string out;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) out += buf.data();
  return {WEXITSTATUS(pclose(p)), out};
}
/// The whole text of a file ("" if it cannot be read).
std::string readText(const std::string& path) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return "";
  std::string text;
  std::array<char, 4096> buf{};
  while (std::fgets(buf.data(), buf.size(), f)) text += buf.data();
  std::fclose(f);
  return text;
}
}  // namespace

TEST(ExperimentCli, UnparsableValuesAreStartUpErrorsNamingTheFlag) {
  const std::string base = std::string("reach --robot ") + EHC_CONFIG_DIR +
                           "/robots/realman_rm65_water2/robot.yaml --out /tmp/ehc_cli_exp ";
  for (const std::string& bad :
       {std::string("--sets 1e1"), std::string("--points 5x"), std::string("--seed -1"),
        std::string("--sets 0"), std::string("--noise maybe"), std::string("--set 3")}) {
    const Result r = run(base + bad);
    EXPECT_EQ(r.code, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find(bad.substr(0, bad.find(' ')) + ":"), std::string::npos)
        << bad << ": " << r.out;
  }
  const Result twice = run(base + "--sets 2 --sets 3");
  EXPECT_EQ(twice.code, 2);
  EXPECT_NE(twice.out.find("--sets: given twice"), std::string::npos) << twice.out;
}

TEST(ExperimentCli, ReachTakesTheProtocolAndTheBaseModel) {
  // --protocol was lost from the reach flags in a merge (every run was the sequence protocol).
  const std::string out = "/tmp/ehc_cli_exp_protocol";
  const std::string base = std::string("reach --robot ") + EHC_CONFIG_DIR +
                           "/robots/realman_rm65_water2/robot.yaml --method neo_e --sets 1 --points 1 --out " + out + " ";
  const Result reset = run(base + "--protocol reset --base-model water2");
  ASSERT_EQ(reset.code, 0) << reset.out;
  const std::string table = readText(out + "/table.md");
  ASSERT_FALSE(table.empty());
  EXPECT_NE(table.find("protocol reset"), std::string::npos) << table;
  const Result bad = run(base + "--protocol random");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("--protocol:"), std::string::npos) << bad.out;
}

TEST(ExperimentCli, ReachAndGraspTakeTheBaseImprecisionLevelAndRecordIt) {
  const std::string out = "/tmp/ehc_cli_exp_imprecision";
  const std::string base = std::string("reach --robot ") + EHC_CONFIG_DIR +
                           "/robots/realman_rm65_water2/robot.yaml --method neo_e --sets 1 --points 1 --out " + out + " ";
  const Result ok = run(base + "--base-imprecision 0.5");
  ASSERT_EQ(ok.code, 0) << ok.out;
  const std::string summary = readText(out + "/summary.json");
  EXPECT_NE(summary.find("\"base_imprecision\":0.5"), std::string::npos) << summary;
  EXPECT_NE(ok.out.find("\"base_imprecision\":0.5"), std::string::npos) << "the summary line";
  EXPECT_NE(readText(out + "/table.md").find("base imprecision level 0.5"), std::string::npos);
  for (const std::string& bad : {std::string("--base-imprecision -1"), std::string("--base-imprecision nan")}) {
    for (const std::string& command : {base, "grasp --method ehc --sets 1 --out " + out + "_grasp "}) {
      const Result r = run(command + bad);
      EXPECT_EQ(r.code, 2) << command << bad << ": " << r.out;
      EXPECT_NE(r.out.find("--base-imprecision:"), std::string::npos) << command << bad << ": " << r.out;
    }
  }
}

TEST(ExperimentCli, ReachTakesTheTargetGeneratorAndItsFields) {
  const std::string out = "/tmp/ehc_cli_exp_generator";
  const std::string base = std::string("reach --robot ") + EHC_CONFIG_DIR +
                           "/robots/realman_rm65_water2/robot.yaml --method neo_e --sets 1 --points 1 --out " + out + " ";
  const Result any = run(base + "--generator any --max-distance 2.5");
  ASSERT_EQ(any.code, 0) << any.out;
  const std::string table = readText(out + "/table.md");
  ASSERT_FALSE(table.empty());
  // The table names the distribution it was measured on, with the overridden field.
  EXPECT_NE(table.find("targets 0-2.5 m apart"), std::string::npos) << table;
  EXPECT_NE(table.find("tilt sphere up to 180 deg"), std::string::npos) << table;
  const Result unknown = run(base + "--generator everywhere");
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.out.find("--generator"), std::string::npos) << unknown.out;
  const Result bad = run(base + "--min-distance 3 --max-distance 2");
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.out.find("min_distance"), std::string::npos) << bad.out;
}

TEST(ExperimentCli, LibraryIsAnExp2OptionAndPosesRunsWithoutIt) {
  const std::string out = "/tmp/ehc_cli_exp_poses";
  const Result ok = run("poses --method ehc --sets 1 --per-set 1 --object-time-limit 1 --out " + out);
  ASSERT_EQ(ok.code, 0) << ok.out;
  EXPECT_FALSE(readText(out + "/summary.json").empty());
  const Result bad = run("poses --method ehc --sets 1 --per-set 1 --library tuning --out " + out + "_bad");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--library"), std::string::npos) << bad.out;
}
