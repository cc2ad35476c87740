// The everyday Exp-2 judged against the objects' true meshes: an attempt record judged (a valid
// grasp attempted, an invalid one where a valid one exists, a grasp attempted where none exists,
// no grasp chosen), the bar's counts (an object without a valid grasp in view is not in the
// denominator), and trials.csv / summary.json / table.md agreeing with each other; then one
// everyday set in-process, every object judged, the columns consistent with the cause column and
// the summary equal to the counts over the rows.

#include "ehc_bringup/grasp_experiment.h"
#include "ehc_perception/convex_polygon.h"
#include "ehc_sim/sim_world.h"

#include "ehc_common/json.h"
#include "ehc_test/temp_dir.h"

#include <gtest/gtest.h>

#include <map>
#include <sstream>

using namespace ehc_bringup;

namespace {

constexpr double kTable = 0.75;  // the default table's top (ehc_sim::TableConfig)

ehc_sim::SceneConfig tableScene() {
  ehc_sim::SceneConfig s;
  s.tables.push_back(ehc_sim::TableConfig{});  // top at 0.75 m, centre (1.9, 0)
  return s;
}

/// A top-down grasp at `origin` closing along world y.
Eigen::Isometry3d topDown(const Eigen::Vector3d& origin) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear().col(1) = Eigen::Vector3d::UnitY();
  T.linear().col(2) = -Eigen::Vector3d::UnitZ();
  T.linear().col(0) = T.linear().col(1).cross(T.linear().col(2));
  T.translation() = origin;
  return T;
}

/// An object of height `h` standing at (1.7, 0) on the table, seen from 0.6 m in front and above.
GraspAttemptRecord record(double h, const std::optional<Eigen::Isometry3d>& locked_grasp) {
  GraspAttemptRecord r;
  ObjectViewRecord v;
  v.t = 3.0;
  v.T_world_object.translation() = Eigen::Vector3d(1.7, 0.0, kTable + 0.5 * h);
  v.T_world_cam.translation() = Eigen::Vector3d(1.2, 0.0, 1.15);
  r.last_seen = v;
  r.end = v;
  r.end.t = 9.0;
  if (locked_grasp) {
    r.locked = r.chosen = true;
    r.grasp.pose = *locked_grasp;
    r.grasp.width = 0.06;
    r.grasp_view = v;
    r.T_world_object_at_choice = v.T_world_object;
  }
  return r;
}

const ehc_perception::GripperGeometry kGripper;

GraspTrial trial(const std::string& method, bool success, const AttemptJudgement& j) {
  GraspTrial t;
  t.method = method;
  t.object = "o";
  t.success = success;
  t.cause = success ? "none" : "closed_empty";
  t.judge = j;
  return t;
}

/// The judge columns of trials.csv by method: counts as JudgeCounts defines them. The row ends
/// with the generator's reason (quoted, may hold commas), after the target selection and the
/// generator's failure; before them the seven judge columns (no commas in them); method and
/// success lead the row.
std::map<std::string, JudgeCounts> countRows(const std::string& csv) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_NE(line.find(",cause,judge_view,valid_exists,valid_reachable_exists,attempted,attempt_valid,grasp_verdict,candidate_verdict,judge_reason,"
                      "target_selection,generator_failure,generator_reason"),
            std::string::npos)
      << line;
  std::map<std::string, JudgeCounts> out;
  while (std::getline(in, line)) {
    std::string rest = line.back() == '"' ? line.substr(0, line.rfind(",\"")) : line.substr(0, line.rfind(','));
    std::string generator[2];  // target selection, generator failure
    for (int k = 1; k >= 0; --k) {
      generator[k] = rest.substr(rest.rfind(',') + 1);
      rest = rest.substr(0, rest.rfind(','));
    }
    std::vector<std::string> tail;
    for (int k = 0; k < 8; ++k) {  // judge_view .. judge_reason
      const std::size_t c = rest.rfind(',');
      tail.insert(tail.begin(), rest.substr(c + 1));
      rest = rest.substr(0, c);
    }
    std::vector<std::string> head;
    std::istringstream h(line);
    for (std::string f; head.size() < 7 && std::getline(h, f, ',');) head.push_back(f);
    if (tail[0].empty()) continue;  // not judged
    JudgeCounts& c = out[head[0]];
    const bool success = head[6] == "1", exists = tail[1] == "1", attempted = tail[3] == "1", valid = tail[4] == "1";
    EXPECT_TRUE(exists || tail[2].empty()) << "reach is judged only where a valid grasp exists: " << line;
    const bool reachable = tail[2] == "1";
    ++c.objects;
    c.attempted += attempted;
    c.attempted_invalid += attempted && !valid;
    c.valid_exists += exists;
    c.grasped_where_exists += exists && success;
    c.attempted_where_none += !exists && attempted;
    c.grasped_where_none += !exists && success;
    c.reach_judged += !tail[2].empty();
    c.reachable_exists += reachable;
    c.grasped_where_reachable += reachable && success;
    EXPECT_FALSE(valid && !attempted) << line;
    EXPECT_EQ(tail[7].rfind("attempted_where_none", 0) == 0, !exists && attempted && !success) << line;
    // The generator's failure and the selection are names of their enums.
    EXPECT_NO_THROW(ehc_perception::graspFailureFromString(generator[1])) << line;
    EXPECT_FALSE(generator[0].empty()) << line;
    if (exists && !success && tail[7] == "no_grasp_chosen") {
      const bool unselected = generator[0] != "selected" && generator[0] != "not_cloud_target";
      ++c.no_grasp_failures[unselected ? "no_target:" + generator[0] : generator[1]];
    }
  }
  return out;
}

/// summary.json's judge counts of every method and table.md's row agree with the rows.
void expectSummaryMatchesRows(const std::string& dir, const GraspExperimentResult& r) {
  const std::map<std::string, JudgeCounts> rows = countRows(ehc_test::readText(dir + "/trials.csv"));
  const ehc_common::Json summary = ehc_common::Json::parse(ehc_test::readText(dir + "/summary.json"));
  const std::string table = ehc_test::readText(dir + "/table.md");
  for (const ehc_common::Json& m : summary["methods"]) {
    const std::string method = m["method"];
    const auto it = rows.find(method);
    ASSERT_NE(it, rows.end()) << method;
    const JudgeCounts& c = it->second;
    const ehc_common::Json& j = m["judge"];
    EXPECT_EQ(j["objects"], c.objects) << method;
    EXPECT_EQ(j["valid_exists"], c.valid_exists) << method;
    EXPECT_EQ(j["grasped_where_exists"], c.grasped_where_exists) << method;
    EXPECT_EQ(j["reach_judged"], c.reach_judged) << method;
    EXPECT_EQ(j["reachable_exists"], c.reachable_exists) << method;
    EXPECT_EQ(j["grasped_where_reachable"], c.grasped_where_reachable) << method;
    EXPECT_EQ(j["attempted"], c.attempted) << method;
    EXPECT_EQ(j["attempted_invalid"], c.attempted_invalid) << method;
    EXPECT_EQ(j["attempted_where_none"], c.attempted_where_none) << method;
    EXPECT_EQ(j["grasped_where_none"], c.grasped_where_none) << method;
    EXPECT_EQ(j["no_grasp_failures"], ehc_common::Json(c.no_grasp_failures)) << method;
    int reasons = 0;
    for (const auto& [reason, n] : j["reasons"].items()) reasons += n.get<int>();
    EXPECT_EQ(reasons, c.objects) << method;
    EXPECT_NE(table.find("| " + method + " | " + std::to_string(c.objects) + " | " + std::to_string(c.valid_exists) + " | " +
                         std::to_string(c.grasped_where_exists) + " ("),
              std::string::npos)
        << table;
  }
  EXPECT_EQ(rows.size(), r.summaries.size());
}

}  // namespace

TEST(EverydayJudge, AttemptsAreJudgedAgainstTheTrueMesh) {
  const ehc_sim::SceneConfig scene = tableScene();
  const ehc_sim::TriangleMesh box = ehc_sim::boxSurface({0.05, 0.05, 0.10});  // top at 0.85 m
  GraspJudgeParams p;
  // A valid top-down grasp 30 mm below the top, attempted.
  const AttemptJudgement good = judgeAttempt(record(0.10, topDown({1.7, 0.0, 0.82})), box, scene, kGripper, p, 1);
  ASSERT_TRUE(good.judged);
  EXPECT_EQ(good.view, "grasp");
  EXPECT_TRUE(good.attempted && good.attemptValid() && good.valid_exists);
  EXPECT_EQ(good.reason(true), "grasped");
  EXPECT_EQ(good.reason(false), "valid_grasp_failed");
  EXPECT_FALSE(good.has_candidate);
  // 20 mm off the centre along the closing axis: invalid, and a valid grasp exists; the candidate
  // it came from (centred) was valid.
  GraspAttemptRecord moved = record(0.10, topDown({1.7, 0.02, 0.82}));
  moved.candidate = GraspCandidate{topDown({1.7, 0.0, 0.82}), 0.06, 1.0};
  const AttemptJudgement off = judgeAttempt(moved, box, scene, kGripper, p, 1);
  EXPECT_TRUE(off.has_candidate);
  EXPECT_EQ(off.candidate_verdict, GraspVerdict::Valid);
  EXPECT_TRUE(off.attempted);
  EXPECT_FALSE(off.attemptValid());
  EXPECT_EQ(off.verdict, GraspVerdict::OutsideOpening);
  EXPECT_TRUE(off.valid_exists);
  EXPECT_EQ(off.reason(false), "invalid_grasp:outside_opening");
  // No grasp chosen: existence from the last view with the object in the image, and what the
  // generator and the cloud target's selection said in it.
  GraspAttemptRecord refused = record(0.10, std::nullopt);
  refused.last_seen.failure = ehc_perception::GraspFailure::TooWide;
  refused.last_seen.reason = "too wide: 0.08 m, across";
  refused.last_seen.target = ehc_control::TargetSelectionStatus::Selected;
  const AttemptJudgement none_chosen = judgeAttempt(refused, box, scene, kGripper, p, 1);
  EXPECT_EQ(none_chosen.generator_failure, ehc_perception::GraspFailure::TooWide);
  EXPECT_EQ(none_chosen.generator_reason, "too wide: 0.08 m, across");
  EXPECT_EQ(noGraspCause(none_chosen), "too_wide");
  AttemptJudgement ambiguous = none_chosen;
  ambiguous.target = ehc_control::TargetSelectionStatus::Ambiguous;
  EXPECT_EQ(noGraspCause(ambiguous), "no_target:" + ehc_control::toString(ehc_control::TargetSelectionStatus::Ambiguous));
  EXPECT_EQ(good.generator_failure, ehc_perception::GraspFailure::None);
  EXPECT_EQ(none_chosen.view, "last_seen");
  EXPECT_FALSE(none_chosen.attempted || none_chosen.chosen);
  EXPECT_TRUE(none_chosen.valid_exists);
  EXPECT_EQ(none_chosen.reason(false), "no_grasp_chosen");
  // A 100 mm cube fits the 70 mm opening nowhere: none exists, attempted or not.
  const ehc_sim::TriangleMesh cube = ehc_sim::boxSurface({0.10, 0.10, 0.10});
  const AttemptJudgement where_none = judgeAttempt(record(0.10, topDown({1.7, 0.0, 0.82})), cube, scene, kGripper, p, 1);
  EXPECT_TRUE(where_none.attempted);
  EXPECT_FALSE(where_none.valid_exists);
  EXPECT_EQ(where_none.reason(false), "attempted_where_none:outside_opening");
  const AttemptJudgement none = judgeAttempt(record(0.10, std::nullopt), cube, scene, kGripper, p, 1);
  EXPECT_FALSE(none.valid_exists);
  EXPECT_EQ(none.reason(false), "none_exists:wider_than_opening");
  // Never in view: the camera at the end; no view at all: not judged.
  GraspAttemptRecord unseen = record(0.10, std::nullopt);
  unseen.last_seen = ObjectViewRecord{};
  EXPECT_EQ(judgeAttempt(unseen, box, scene, kGripper, p, 1).view, "end");
  unseen.end = ObjectViewRecord{};
  EXPECT_FALSE(judgeAttempt(unseen, box, scene, kGripper, p, 1).judged);

  // The bar's counts: the cube (none exists) is not in the denominator; its attempt is counted.
  GraspExperimentResult r;
  GraspMethodSummary s;
  s.method = "ehc";
  for (const GraspTrial& t : {trial("ehc", true, good), trial("ehc", false, off), trial("ehc", false, none_chosen),
                              trial("ehc", false, where_none), trial("ehc", false, none), trial("ehc", false, AttemptJudgement{})}) {
    r.trials.push_back(t);
    s.judge.add(t);
  }
  EXPECT_EQ(s.judge.objects, 5);
  EXPECT_EQ(s.judge.valid_exists, 3);
  EXPECT_EQ(s.judge.grasped_where_exists, 1);
  EXPECT_EQ(s.judge.attempted, 3);
  EXPECT_EQ(s.judge.attempted_invalid, 2);
  EXPECT_EQ(s.judge.attempted_where_none, 1);
  EXPECT_EQ(s.judge.no_grasp_failures, (std::map<std::string, int>{{"too_wide", 1}}));
  EXPECT_EQ(s.judge.reasons.at("no_grasp_chosen"), 1);
  r.summaries.push_back(s);
  GraspExperimentParams params;
  params.config_dir = EHC_CONFIG_DIR;
  const ehc_test::TempDir dir("ehc_everyday_judge");
  writeGraspResults(dir.path, params, r, "");
  expectSummaryMatchesRows(dir.path, r);
  EXPECT_NE(ehc_test::readText(dir.path + "/table.md").find("| ehc | 5 | 3 | 1 (33.3 %) | 0 | 0 (0.0 %) | 1 | 3 (2) | 0 |"), std::string::npos);
}

TEST(EverydayJudge, TheRobotsReachSplitsTheObjectsWithAValidGrasp) {
  // With a reach test: a valid chosen grasp the robot reaches makes a reachable one exist without
  // a search; one it does not reach sends the search on to the other valid grasps, which finds
  // one where the test accepts a tilted approach and none where it accepts nothing; where no
  // valid grasp exists, reach is not judged.
  const ehc_sim::SceneConfig scene = tableScene();
  const ehc_sim::TriangleMesh box = ehc_sim::boxSurface({0.05, 0.05, 0.10});
  GraspJudgeParams p;
  p.accept_checks = 25;
  const GraspAttemptRecord rec = record(0.10, topDown({1.7, 0.0, 0.82}));
  int calls = 0;
  const AttemptJudgement any = judgeAttempt(rec, box, scene, kGripper, p, 1, [&](const Eigen::Isometry3d&) { return ++calls > 0; });
  EXPECT_TRUE(any.reach_judged && any.reachable_exists);
  EXPECT_EQ(calls, 1) << "the chosen grasp, valid and reached: no search";
  const auto tilted = [](const Eigen::Isometry3d& g) { return g.linear().col(2).z() > -0.9; };
  const AttemptJudgement leaning = judgeAttempt(rec, box, scene, kGripper, p, 1, tilted);
  EXPECT_TRUE(leaning.reach_judged && leaning.reachable_exists);
  const AttemptJudgement out = judgeAttempt(rec, box, scene, kGripper, p, 1, [](const Eigen::Isometry3d&) { return false; });
  EXPECT_TRUE(out.reach_judged && out.valid_exists);
  EXPECT_FALSE(out.reachable_exists);
  EXPECT_EQ(out.reach_refused, p.accept_checks);
  EXPECT_FALSE(judgeAttempt(rec, box, scene, kGripper, p, 1).reach_judged) << "no reach test";
  const AttemptJudgement none = judgeAttempt(rec, ehc_sim::boxSurface({0.10, 0.10, 0.10}), scene, kGripper, p, 1, tilted);
  EXPECT_FALSE(none.valid_exists || none.reach_judged || none.reachable_exists);
  // The counts: objects with a valid grasp, those with a reachable one, those grasped.
  JudgeCounts c;
  for (const GraspTrial& t : {trial("ehc", true, any), trial("ehc", false, leaning), trial("ehc", true, out),
                              trial("ehc", false, none)})
    c.add(t);
  EXPECT_EQ(c.valid_exists, 3);
  EXPECT_EQ(c.reach_judged, 3);
  EXPECT_EQ(c.reachable_exists, 2);
  EXPECT_EQ(c.grasped_where_reachable, 1);
}

TEST(EverydayJudge, TheTableTopUnderAPointIsItsSupport) {
  ehc_sim::SceneConfig scene = tableScene();
  ehc_sim::TableConfig turned;
  turned.center = Eigen::Vector2d(-2.0, 1.0);
  turned.size = Eigen::Vector2d(0.6, 1.0);
  turned.yaw = 0.5;
  turned.height = 0.9;
  scene.tables.push_back(turned);
  const auto top = tableTopUnder(scene, Eigen::Vector2d(1.9, 0.5));
  ASSERT_TRUE(top);
  EXPECT_DOUBLE_EQ(top->height, kTable);
  ASSERT_EQ(top->footprint.size(), 4u);
  EXPECT_TRUE(top->footprint[0].isApprox(Eigen::Vector2d(1.5, -0.6)));
  EXPECT_TRUE(top->footprint[2].isApprox(Eigen::Vector2d(2.3, 0.6)));
  // The turned table: its corners 0.3 and 0.5 m from its centre along its own axes.
  const Eigen::Vector2d inside = turned.center + Eigen::Rotation2Dd(0.5) * Eigen::Vector2d(0.25, 0.45);
  const auto t2 = tableTopUnder(scene, inside);
  ASSERT_TRUE(t2);
  EXPECT_DOUBLE_EQ(t2->height, 0.9);
  EXPECT_TRUE(t2->valid());
  EXPECT_TRUE(t2->footprint[2].isApprox(turned.center + Eigen::Rotation2Dd(0.5) * Eigen::Vector2d(0.3, 0.5)));
  EXPECT_GT(ehc_perception::polygonArea(t2->footprint), 0.0) << "counter-clockwise";
  EXPECT_FALSE(tableTopUnder(scene, turned.center + Eigen::Rotation2Dd(0.5) * Eigen::Vector2d(0.35, 0.0))) << "the floor";
}

TEST(EverydayJudge, OneEverydaySetIsJudgedObjectByObject) {
  GraspExperimentParams p;
  p.config_dir = EHC_CONFIG_DIR;
  p.sets = 1;
  p.seed = 5;  // grasped, no grasp chosen (no_grasp), a valid grasp stalled on the way in
  p.library_split = "validation";
  p.timing = false;
  const GraspExperimentResult r = GraspExperiment(p, {"ehc"}).run();
  ASSERT_EQ(r.trials.size(), 3u);
  for (const GraspTrial& t : r.trials) {
    const AttemptJudgement& j = t.judge;
    SCOPED_TRACE(t.object + ": cause " + t.cause + ", " + j.view + ", " + j.reason(t.success));
    ASSERT_TRUE(j.judged);
    // No lock before these causes; a lock is judged from the view its grasp came from.
    if (t.cause == "no_grasp" || t.cause == "not_seen" || t.cause == "no_target") {
      EXPECT_FALSE(j.attempted);
    }
    if (t.cause == "closed_empty" || t.cause == "dropped" || t.success) {
      EXPECT_TRUE(j.attempted);
    }
    if (j.attempted) {
      EXPECT_EQ(j.view, "grasp");
    }
    if (j.chosen) {  // a cloud target's grasps are candidates
      EXPECT_TRUE(j.has_candidate);
    }
    if (t.success) {
      EXPECT_TRUE(j.valid_exists || j.reason(t.success) == "grasped_where_none");
    }
    EXPECT_EQ(j.reach_judged, j.valid_exists) << "the run's robot judges reach where a valid grasp exists";
    if (t.success && j.valid_exists) {
      EXPECT_TRUE(j.reachable_exists) << "grasped: the robot reached a valid grasp";
    }
  }
  const ehc_test::TempDir dir("ehc_everyday_set");
  writeGraspResults(dir.path, p, r, "");
  expectSummaryMatchesRows(dir.path, r);
}
