#pragma once
// GraspExperiment: paper Exp-2 (Table III: grasp three objects on a table in sequence) and Exp-3
// (Table IV: one object, forward / downward / sideways grasps, TfM with and without MPBS) as
// deterministic in-process protocols on GraspPipeline. No ROS master.
//
// Exp-2 (`table`): config/scenes/table_three_objects.yaml, the demo's sequencer (front, middle,
//   back; 30 s per object), one run per (method, set). Exp-3 (`poses`):
//   config/scenes/single_object.yaml, config/demo/grasp_single_<approach>.yaml, one run per
//   (method, set, index, approach). Every run starts from the scene's start pose.
// Sets: run seed = seed * 1000 + set * 10 + index (noise of Table I, camera noise) and a seeded
//   jitter of every object's placement: uniform in +-jitter_xy (x, y) and +-jitter_yaw_deg (yaw),
//   drawn from the same run seed; so no two sets repeat one run.
// Methods: tsmm, neo_c, neo_e (MPBS off: the baselines' plain PBVS to the goal), ehc (MPBS on);
//   Exp-3: neo_nompbs (neo_e, MPBS off), ehc_nompbs (ehc, MPBS off), ehc (MPBS on).

#include "ehc_bringup/grasp_judge.h"
#include "ehc_bringup/grasp_pipeline.h"
#include "ehc_bringup/reach_experiment.h"
#include "ehc_sim/object_library.h"

#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ehc_bringup {

enum class GraspProtocol { Table, Poses };  ///< Exp-2, Exp-3

struct GraspMethod {
  std::string name;
  ehc_control::ControlMode mode = ehc_control::ControlMode::Ehc;
  bool mpbs = true;
};
/// tsmm | neo_c | neo_e | ehc | ehc_place | neo_nompbs | ehc_nompbs; throws "[GraspExperiment] ..." otherwise.
GraspMethod graspMethod(const std::string& name);
/// The methods of a protocol ("all": every one, in the paper's table order).
std::vector<std::string> graspMethodNames(GraspProtocol protocol, const std::string& method);

struct GraspExperimentParams {
  GraspProtocol protocol = GraspProtocol::Table;
  std::string config_dir = "config";
  std::string robot;           ///< robot name or robot.yaml (GraspPipelineFiles::robot); "" = the config files'
  std::string scene;           ///< "" = the protocol's scene
  int sets = 15;
  int per_set = 5;             ///< Exp-3: grasps per approach per set
  unsigned seed = 1;
  double jitter_xy = 0.01;     ///< m, object placement jitter (uniform +-)
  double jitter_yaw_deg = 3.0; ///< deg
  int jobs = 1;                ///< runs in parallel (threads, one pipeline each)
  double distant_threshold = 0.5;  ///< m: cycles with |e| above are "distant"
  double trace_period = 0.1;   ///< s of sim time between trace samples (plots)
  bool timing = true;          ///< wall seconds per pipeline stage (counters; never in the results' logic)
  /// Base model of the simulator (--base-model): unset = the sim file's (bullet_sim.yaml: ideal);
  /// water2 = the RealMan Water2 chain, whose /odom estimate is what the stack sees
  /// (GraspPipeline::stackView).
  std::optional<ehc_sim::BaseModelType> base_model;
  /// Base imprecision level of the simulator (--base-imprecision; ehc_sim::BaseImprecisionParams,
  /// on top of the base model): unset = the sim file's (bullet_sim.yaml: 0, off).
  std::optional<double> base_imprecision;
  /// s, WAIT_TARGET..LIFT per object (--object-time-limit): unset = the sequencer file's (30 s).
  std::optional<double> object_time_limit;
  /// Exp-2 with everyday objects (--library): "" = the scene's own objects (tagged). "validation"
  /// or "tuning": every run replaces the scene's objects by as many objects of that half of the
  /// object library (<config_dir>/objects/library.yaml), drawn from the run seed (no object
  /// twice, none overlapping another's place), each standing where the scene's object stood
  /// (on its support, turned by a random yaw), without a tag; the sequencer's object i is
  /// named after its library object and its target is `nearest` the place's centre within
  /// library_radius (the scene's `targets:`).
  std::string library_split;
  double library_radius = 0.08;  ///< m
  void validate() const;       ///< throws "[GraspExperiment] ..."
};

/// A perceived robot-obstacle pair of a grasp (or a method) for the safety table: its distance,
/// the link and its stop distance d_s, the scene body nearest to the perceived obstacle point
/// (ground truth: "table_top", an object's name, "floor"), the sequencer phase.
struct ObstacleExtreme {
  bool found = false;      ///< false: no pair within the influence distance (the rest unset)
  double distance = 0.0;   ///< m; <= 0: penetration (the worst case, never "no pair")
  double stop = 0.0;       ///< m, d_s of the link
  std::string link, body, phase;
  double margin() const { return distance - stop; }
  /// Takes `d` if it is smaller in distance (by_margin false) or in distance - d_s (true), or the first.
  void take(const ObstacleExtreme& d, bool by_margin) {
    if (!d.found) return;
    if (!found || (by_margin ? d.margin() < margin() : d.distance < distance)) *this = d;
  }
};

/// One object's attempt judged against the object's true mesh (GraspJudge), from what the
/// pipeline recorded (GraspAttemptRecord): the grasp the sequencer chose and whether a valid
/// grasp existed in the view it came from. The view (`view`): `grasp`, the one the chosen grasp's
/// candidate set came from; without a chosen grasp from a candidate set, `last_seen`, the last
/// depth view taken for the object's grasps in which its true centre was in the image; without
/// one, `end`, the camera when the object's attempt ended. The view's camera gives the judge its
/// view direction (the approach rule); the object stands where it was at the lock (at the end of
/// the attempt for a grasp chosen but never locked; in the view without a chosen grasp).
struct AttemptJudgement {
  bool judged = false;         ///< false: not judged (no library object, or the run ended first)
  std::string view;            ///< grasp | last_seen | end
  bool chosen = false;         ///< a grasp was chosen (GraspAttemptRecord::chosen)
  bool attempted = false;      ///< it was locked: the gripper went for it
  GraspVerdict verdict = GraspVerdict::NotFinite;  ///< the chosen grasp's (chosen only)
  /// The generator's candidate it came from, as generated (GraspAttemptRecord::candidate): the
  /// verdict tells a generator's invalid grasp from one the selection's turn made invalid.
  bool has_candidate = false;
  GraspVerdict candidate_verdict = GraspVerdict::NotFinite;
  /// A valid grasp exists in the view: the chosen grasp is valid, or the existence search
  /// (GraspJudge::findValidGrasp, run only when it is not) finds one.
  bool valid_exists = false;
  GraspVerdict search_verdict = GraspVerdict::Valid;  ///< none exists: the search's commonest verdict
  /// With a reach test (judgeAttempt's `reachable`) and a valid grasp in the view: whether one of
  /// the valid grasps is one the robot reaches (the chosen grasp, else the existence search with
  /// the reach test as its acceptance: GraspJudge::findValidGrasp). A miss where none is reachable
  /// is the robot's workspace, not the grasp's or the approach's.
  bool reach_judged = false;
  bool reachable_exists = false;
  int reach_refused = 0;  ///< valid grasps the search found out of reach
  /// Grasps the search judged (0: no closing line through the mesh fits the opening; 0 also
  /// when it did not search).
  int search_candidates = 0;
  /// The grasp generator's outcome in the view (ObjectViewRecord::failure / reason; None where
  /// it gave grasps, e.g. the view a chosen grasp came from) and, for a target without a tag,
  /// the cloud target's selection there.
  ehc_perception::GraspFailure generator_failure = ehc_perception::GraspFailure::None;
  std::string generator_reason;
  ehc_control::TargetSelectionStatus target = ehc_control::TargetSelectionStatus::NotCloudTarget;
  bool attemptValid() const { return attempted && verdict == GraspVerdict::Valid; }
  /// One token for the bar (a valid grasp exists -> grasped and lifted; none -> not attempted):
  /// grasped; valid_grasp_failed (a valid grasp attempted, not lifted: the cause column says
  /// why); invalid_grasp:<verdict> (attempted); not_locked:<verdict> (chosen, the object failed
  /// before the lock); no_grasp_chosen; and where none exists attempted_where_none:<verdict>,
  /// grasped_where_none (the judge is stricter than the simulator) or none_exists:<search verdict>
/// (none_exists:wider_than_opening when the search found no closing line that fits the opening).
  std::string reason(bool success) const;
};

/// Judges `record` (world frame, ground truth) against `mesh` (the object's surface in its body
/// frame) standing on the top of `scene`'s table under it (the floor if none); the existence
/// search seeded with `seed`. Not judged (judged false) when the record has no view at all.
/// `reachable` (optional): whether the robot reaches a grasp (TCP pose, world; e.g.
/// GraspReach::judge of it and its pre-grasp), for AttemptJudgement::reachable_exists.
AttemptJudgement judgeAttempt(const GraspAttemptRecord& record, const ehc_sim::TriangleMesh& mesh, const ehc_sim::SceneConfig& scene,
                              const ehc_perception::GripperGeometry& gripper, const GraspJudgeParams& params, unsigned seed,
                              const GraspReachable& reachable = {});

/// The top of `scene`'s table under `xy` (world) as a support surface (its height and its
/// footprint's corners), the highest if several; nullopt on the floor.
std::optional<SupportSurface> tableTopUnder(const ehc_sim::SceneConfig& scene, const Eigen::Vector2d& xy);

/// One grasp (one row of trials.csv).
struct GraspTrial {
  std::string method;
  int set = 0, index = 0;
  unsigned seed = 0;
  std::string object, approach;
  bool success = false;
  double time_s = 0.0;
  double tfm = 0.0, tfm_until_switch = 0.0, controller_tfm = 0.0;
  std::string failed_phase, reason;
  std::string cause = "none";  ///< GraspResult::cause (toString(GraspCause)); "none" on success
  /// The object's time limit fired: its cause (GraspResult::stallCause: a MotionLimit name) and
  /// what it names (the pinned joint; the link held at its stop distance and the scene body of
  /// the obstacle point; the detail line). All "" otherwise.
  std::string stall_cause, stall_joint, stall_link, stall_body, stall_detail;
  double close_offset = -1.0;        ///< m, GraspResult::close_offset
  long contact_steps = 0;            ///< sim steps with a robot-scene or self collision
  long joint_limit_violations = 0;   ///< arm joint samples outside the limits
  /// Perceived link-obstacle pairs against the scene: the smallest distance and the smallest
  /// margin distance - d_s (< 0: closer than d_s). The object being grasped counts as scene until
  /// the grasp is locked (APPROACH); from PRE_GRASP on, the hand must come close to it (the
  /// obstacle map excludes it from GRASP on), and its pairs go to `grasped` instead.
  ObstacleExtreme nearest, tightest;
  ObstacleExtreme grasped;           ///< the object being grasped, PRE_GRASP on: smallest distance
  /// Ground truth (the simulator's object pose), to trace a grasp that closed on nothing: the
  /// object's centre in the locked grasp's frame at the lock (x, y = finger closing axis,
  /// z = approach; the plan's error is its difference from the tag target's grasp offset), and
  /// in the TCP frame when the gripper was commanded to close. m; NaN: no lock / never closed.
  Eigen::Vector3d lock_centre_in_grasp = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector3d close_centre_in_tcp = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  /// Ground truth at the lock: the angle of the grasp's finger closing axis (y) from the nearest
  /// axis of the object's frame (a box's face normals), deg; NaN: no lock.
  double lock_closing_axis_error_deg = std::numeric_limits<double>::quiet_NaN();
  /// Everyday objects (library_split): the attempt judged against the object's true mesh.
  AttemptJudgement judge;
};

/// Why no grasp was chosen for a judged attempt, one token: "no_target:<selection>" when a cloud
/// target was not selected in the judged view (ehc_control::TargetSelectionStatus), else the
/// generator's failure there (toString(GraspFailure)).
std::string noGraspCause(const AttemptJudgement& j);

/// Counts over judged grasps (summary.json "judge", table.md): the everyday Exp-2's bar is
/// grasped_where_exists / valid_exists >= 90 % and attempted_where_none == 0.
struct JudgeCounts {
  int objects = 0;               ///< grasps judged
  int valid_exists = 0;          ///< a valid grasp exists in the view
  int grasped_where_exists = 0;  ///< ... and the object was grasped and lifted
  int attempted = 0;             ///< a grasp locked (attempted)
  int attempted_invalid = 0;     ///< ... judged invalid
  int attempted_where_none = 0;  ///< a grasp attempted where no valid grasp exists in the view
  int grasped_where_none = 0;    ///< lifted although no valid grasp exists (the judge is stricter)
  /// Of the objects with a valid grasp in view, those judged for reach (AttemptJudgement::
  /// reach_judged), those where a valid grasp is one the robot reaches, and those grasped.
  int reach_judged = 0, reachable_exists = 0, grasped_where_reachable = 0;
  /// Judged grasps per outcome (AttemptJudgement::reason), and the misses where a valid grasp
  /// exists and none was chosen per the generator's failure in the judged view (toString of
  /// GraspFailure; "no_target:<selection>" when a cloud target was not selected there).
  std::map<std::string, int> reasons, no_grasp_failures;
  void add(const GraspTrial& t);
};

/// ‖TCP - object‖ (ground truth) and the commanded speeds (commandSpeeds), sampled every
/// trace_period of an object's attempt.
struct GraspTraceSample {
  std::string method;
  int set = 0, index = 0;
  std::string object;
  double t = 0.0;  ///< s since the object's attempt began
  double distance = 0.0, base_speed = 0.0, base_turn = 0.0, arm_speed = 0.0;
  std::string phase;  ///< the sequencer's phase
  /// Ground truth, from the grasp lock on (NaN before): the true TCP in the locked grasp's frame
  /// (x, y = closing axis, z = approach; z < 0 before the grasp point), m.
  Eigen::Vector3d tcp_in_grasp = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  double object_moved = 0.0;  ///< m, the object's true displacement since the run began
};

struct GraspMethodSummary {
  std::string method;
  std::string base_model;          ///< the simulator's base model (ideal | water2)
  double base_imprecision = 0.0;   ///< its base imprecision level (0 = off)
  int grasps = 0, successes = 0;
  double mean_time_s = 0.0;           ///< over successful grasps
  SpeedMeans distant, close;          ///< mean |commanded speed| (Exp-1's definition)
  std::map<std::string, std::pair<double, int>> tfm;  ///< approach -> (mean TfM, grasps)
  long contact_steps = 0, joint_limit_violations = 0;
  std::map<std::string, int> stall_causes;  ///< grasps whose time limit fired, per cause (GraspTrial::stall_cause)
  ObstacleExtreme nearest, tightest, grasped;  ///< over every grasp of the method (see GraspTrial)
  JudgeCounts judge;  ///< judged grasps only (library_split)
  double sim_time_s = 0.0, wall_time_s = 0.0;
};

struct GraspExperimentResult {
  std::vector<GraspMethodSummary> summaries;
  std::vector<GraspTrial> trials;
  std::vector<GraspTraceSample> trace;
  PipelineCounters counters;          ///< summed over every run
  double sim_time_s = 0.0;
  /// Runs planned and completed: fewer completed when a stop signal arrived
  /// (ehc_common::stopRequested): the result then holds the completed runs only.
  int runs_planned = 0, runs_done = 0;
  bool partial() const { return runs_done < runs_planned; }
};

class GraspExperiment {
 public:
  /// progress(done, total, text) after every run (from the calling thread's view: serialised).
  /// A stop signal (ehc_common::stopRequested) ends the runs in progress and starts no more:
  /// run() returns the completed ones (GraspExperimentResult::partial).
  using Progress = std::function<void(int done, int total, const std::string& text)>;

  GraspExperiment(const GraspExperimentParams& params, std::vector<std::string> methods);
  GraspExperimentResult run(const Progress& progress = nullptr) const;

  /// The pipeline configuration of one run (scene jittered with `seed`) — for tests and tools.
  GraspPipelineConfig runConfig(const std::string& method, const std::string& approach, unsigned seed) const;

 private:
  struct RunSpec {
    std::string method, approach;
    int set = 0, index = 0;
    unsigned seed = 0;
  };
  struct RunOutput;
  RunOutput runOne(const RunSpec& spec) const;

  GraspExperimentParams params_;
  std::vector<std::string> methods_;
  std::map<std::string, GraspPipelineConfig> base_;  ///< per approach ("" for Exp-2)
  std::optional<ehc_sim::ObjectLibrary> library_;     ///< library_split set
};

/// Replaces the objects of `cfg`'s scene by objects of `library`'s `split` half drawn with `seed`
/// (see GraspExperimentParams::library_split): scene objects, targets, sequencer names; no tag
/// targets. Throws "[GraspExperiment] ..." when the half has fewer objects than the scene or no
/// draw of 1000 fits the places.
void placeLibraryObjects(GraspPipelineConfig* cfg, const ehc_sim::ObjectLibrary& library, const std::string& split,
                         double radius, unsigned seed);

/// Paper figures (DESIGN.md section 10, paper Tables III / IV) printed beside the measured ones.
/// Writes DIR/table.md, trials.csv, summary.json, trace.csv.
void writeGraspResults(const std::string& dir, const GraspExperimentParams& params,
                       const GraspExperimentResult& result, const std::string& notes);
/// Wall seconds per pipeline stage and per sim second, one line (`make bench`, stderr).
std::string pipelineStageCosts(const PipelineCounters& c, double sim_time_s);
/// One JSON object per method summary (summary.json "methods"), the project's number format.
ehc_common::Json graspSummaryJsonValue(const GraspMethodSummary& s);
std::string graspSummaryJson(const GraspMethodSummary& s);

}  // namespace ehc_bringup
