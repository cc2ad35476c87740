#pragma once
// GraspJudge: a parallel-jaw grasp judged against an object's TRUE triangle mesh (not a cloud),
// and the search for a valid grasp on that mesh: the oracle that says whether a grasp generator's
// grasp holds and whether any grasp exists in a view (ehc_object_library judge). ROS-free.
//
// The gripper (ehc_perception::GripperGeometry, grasp frame: z = approach, y = closing axis,
// origin between the fingers on the closing line) opens fully (max_width) before it moves in, so
// the judge places the fingers' inner faces at y = +-max_width / 2 whatever width the grasp asks
// for. A grasp is valid when, in this order:
//  1. its approach is one the hand can use: within max_approach_tilt_deg of straight down and,
//     with a view direction, within max_view_angle_deg of it (the hand comes from the camera's
//     side: the camera is on the hand; both 95 deg by default, the generator's max_approach_tilt_deg);
//  2. both contacts lie on the closing line inside the opening: a ray cast along the closing axis
//     from each finger's inner face towards the other meets the mesh entering it; no crossing at
//     all: nothing between the fingers. A contact is outside the opening (the object too wide
//     there, or the grasp off its centre) when that ray's first crossing leaves the mesh, or when
//     the ray from the finger's inner face outwards first leaves it (the face is inside the object);
//  3. the contacts' surface normals (the triangles' outward normals) are within the friction cone
//     atan(mu) of the closing axis;
//  4. the fingers' and the palm's boxes, swept along the approach from the pre-grasp
//     (pregrasp_distance back along z) to the grasp, stay above the table top and do not cross
//     the mesh (FCL: boxes against the mesh's BVH).
// Rays: Bullet's BVH of the triangles; collisions: FCL. The mesh's triangles must be wound with
// outward normals (the simulator's meshes and primitive surfaces are). A swept box entirely inside
// the solid crosses no triangle; every sweep starts 0.1 m back, outside any graspable object.
//
// Existence (findValidGrasp): candidate grasps sampled from the true mesh, judged until one is
// valid. Surface points p are drawn uniformly by area (seeded). Closing axes at p: its outward
// normal n and, for a tilted n, n's horizontal part (closing parallel to the table, as across a
// lying handle); along each, the ray from p into the object meets the opposite side q within the
// opening (the first crossing, leaving the mesh) and the grasp centre is the midpoint of p and q.
// Approaches: approach_steps directions perpendicular to the closing axis (evenly spaced, random
// phase) and the ones nearest straight down and the view direction, those that pass rule 1.
// A sampling search, not a proof: where it finds none a narrow grasp may still exist (more
// samples search more; judgeView also counts a valid grasp of the generator's as one).

#include "ehc_bringup/object_view.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_sim/triangle_mesh.h"

#include <Eigen/Geometry>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace ehc_bringup {

/// Why a grasp is (in)valid (one string map: toString / graspVerdictFromString).
enum class GraspVerdict {
  Valid,
  NotFinite,          ///< the pose has a non-finite or non-rotation part
  ApproachExcluded,   ///< approach too far from straight down or from the view direction
  OutsideOpening,     ///< a contact outside the opening: the object reaches past a finger's inner face on the closing line
  NothingBetween,     ///< the closing line meets nothing between the fingers
  OutsideFrictionCone,  ///< a contact normal is more than atan(mu) off the closing axis
  HitsTable,          ///< a finger or the palm reaches below the table top on the way in
  FingerCollides,     ///< a finger's sweep crosses the object
  PalmCollides,       ///< the palm's sweep crosses the object
};
std::string toString(GraspVerdict v);
GraspVerdict graspVerdictFromString(const std::string& s);  ///< throws "[GraspJudge] unknown ..."

struct GraspJudgeParams {
  double friction_coefficient = 0.5;   ///< mu of the contacts: cone half-angle atan(mu)
  double pregrasp_distance = 0.10;     ///< m, sweep start back along the approach (the sequencer's)
  double max_approach_tilt_deg = 95.0; ///< approach vs straight down (the generator's)
  double max_view_angle_deg = 95.0;    ///< approach vs the view direction (when one is given)
  int samples = 2000;                  ///< existence: surface points drawn
  int approach_steps = 12;             ///< existence: approaches around each closing axis
  /// existence with an acceptance test (findValidGrasp's `accept`, e.g. the robot's reach): at
  /// most this many valid grasps are tested, then the search ends without one
  int accept_checks = 100;
  void validate() const;               ///< throws std::invalid_argument "[GraspJudge] ..."
};

struct GraspJudgement {
  GraspVerdict verdict = GraspVerdict::NotFinite;
  bool valid() const { return verdict == GraspVerdict::Valid; }
  /// m, distance between the two contacts on the closing line (0 if there are not two).
  double width = 0.0;
  /// m, where the closing pads stop (closedWidth; judgeView fills it for the best grasp).
  double closed_width = 0.0;
  /// deg, each contact's normal from the closing axis (-1 if that contact does not exist);
  /// [0]: the finger on -y, [1]: on +y.
  std::array<double, 2> contact_angle_deg = {{-1.0, -1.0}};
  std::array<Eigen::Vector3d, 2> contact = {{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}};  ///< world
};

/// An acceptance test of a valid grasp (grasp frame in the world), e.g. the robot's reach.
using GraspAcceptance = std::function<bool(const Eigen::Isometry3d& grasp)>;

struct GraspExistence {
  bool exists = false;
  int candidates = 0;  ///< grasps judged (the search stops at the first valid one)
  Eigen::Isometry3d grasp = Eigen::Isometry3d::Identity();  ///< the valid grasp found
  std::map<GraspVerdict, int> verdicts;  ///< of the candidates judged
  int refused = 0;  ///< valid grasps the acceptance test refused (findValidGrasp's `accept`)
  GraspVerdict commonest() const;         ///< the commonest invalid verdict (Valid if none)
};

class GraspJudge {
 public:
  /// `mesh` in its body frame, posed in the world by `T_world_object`; the table top is the plane
  /// z = table_height (world, z up). `view_direction` (world, camera towards the object; zero:
  /// no view rule). Throws "[GraspJudge] ..." on an empty mesh or bad parameters.
  GraspJudge(const ehc_sim::TriangleMesh& mesh, const Eigen::Isometry3d& T_world_object, double table_height,
             const ehc_perception::GripperGeometry& gripper, const GraspJudgeParams& params,
             const Eigen::Vector3d& view_direction = Eigen::Vector3d::Zero());
  ~GraspJudge();
  GraspJudge(const GraspJudge&) = delete;
  GraspJudge& operator=(const GraspJudge&) = delete;

  /// The grasp (grasp frame in the world) judged as the header says.
  GraspJudgement judge(const Eigen::Isometry3d& grasp) const;
  /// Candidates sampled from the mesh with `seed` (same seed, same candidates), judged until one
  /// is valid and, with `accept`, accepted by it (e.g. a grasp the robot reaches: the other
  /// approaches round a refused grasp's closing axis are judged next); at most
  /// params.accept_checks valid grasps are put to `accept`.
  GraspExistence findValidGrasp(unsigned seed, const GraspAcceptance& accept = {}) const;

  /// The opening at which the closing fingers stop: the object's extent along the closing axis
  /// within the fingers' slab (finger breadth x finger length), from rays cast from each finger's
  /// inner face towards the other on a grid of `step` m over the pad; 0 if no ray meets the mesh.
  /// What a generator's measured width estimates.
  double closedWidth(const Eigen::Isometry3d& grasp, double step = 0.002) const;

  /// First crossing of the mesh by the segment from `from` to `to` (world): false if none;
  /// else its point and the crossed triangle's outward normal (world).
  bool firstHit(const Eigen::Vector3d& from, const Eigen::Vector3d& to, Eigen::Vector3d* point,
                Eigen::Vector3d* normal) const;

 private:
  bool approachAllowed(const Eigen::Vector3d& approach) const;
  GraspVerdict closingLine(const Eigen::Isometry3d& grasp, GraspJudgement* out) const;
  GraspVerdict sweep(const Eigen::Isometry3d& grasp) const;
  /// Existence: the candidates of surface point `p` closing along `y` (the outward side of p);
  /// true when the search ends: one is valid and accepted (then in `ex`), or the acceptance
  /// checks are used up.
  bool tryAxis(const Eigen::Vector3d& p, const Eigen::Vector3d& y, double phase, const GraspAcceptance& accept,
               GraspExistence* ex) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
  ehc_perception::GripperGeometry gripper_;
  GraspJudgeParams params_;
  Eigen::Vector3d view_;
  double table_height_;
};

/// One library object's view judged: the generator's grasps (generateForTarget with the object's
/// true centre as the target, as the grasp node runs it) against the true mesh.
struct ViewJudgement {
  /// A valid grasp exists in the view: the search found one, or one of the generator's top five
  /// is valid (then the search missed it: search_missed).
  bool exists = false;
  bool search_missed = false;
  GraspExistence existence;
  ehc_perception::GraspResult result;  ///< the generator's
  GraspJudgement best;                 ///< its best grasp's (NotFinite if none)
  /// Its best grasp's without the view rule (approaches from any side within the tilt limit: a
  /// mobile base could walk round); the same as `best` unless that is approach_excluded.
  GraspJudgement best_any_side;
  int top5_valid = 0;                  ///< valid grasps among its first five
  int first_valid_rank = 0;            ///< 1-based rank of its first valid grasp in the top five, 0: none
};
ViewJudgement judgeView(const ObjectViewCloud& view, const ehc_perception::GraspGenerator& generator,
                        const ehc_perception::GraspTargetingParams& targeting, const GraspJudgeParams& params,
                        unsigned seed);

/// Every object of a library split seen from random views, the generator's grasps judged
/// (ehc_object_library judge). View v of object o is drawn from the seed sequence (seed, o's
/// library seed, v): distance, elevation, azimuth uniform in their ranges; then the depth noise's
/// and the existence search's seeds. Same seed, same rows, whichever split is chosen.
struct LibraryJudgeParams {
  std::string split = "all";  ///< tuning, validation or all
  int views = 2;              ///< per object
  unsigned seed = 1;
  double min_distance = 0.5, max_distance = 0.7;            ///< m, camera to the object's centre
  double min_elevation_deg = 30.0, max_elevation_deg = 60.0;
  GraspJudgeParams judge;
  void validate() const;  ///< throws std::invalid_argument "[GraspJudge] ..."
};

struct JudgedView {
  std::string object, kind, split;
  int view = 0;
  ObjectView pose;
  unsigned noise_seed = 0;
  ViewJudgement judgement;
};

/// Judges every view; `progress` (if set) is called after each.
std::vector<JudgedView> judgeLibrary(const ehc_sim::ObjectLibrary& library, const ehc_sim::SimConfig& sim,
                                     const ehc_perception::GraspGenerator& generator,
                                     const ehc_perception::GraspTargetingParams& targeting, const LibraryJudgeParams& params,
                                     const std::function<void(const JudgedView&, std::size_t done, std::size_t total)>& progress);

/// One CSV line per view (header first): object, split, view, exists, the generator's status,
/// its best grasp's verdict, widths (measured by the generator vs between the true contacts), top 5.
std::string judgedViewsCsv(const std::vector<JudgedView>& views);
/// Markdown: per split, the views where a valid grasp exists and how many of them got a valid
/// best grasp / a valid grasp in the top five, and the grasps proposed where none exists.
std::string judgedViewsSummary(const std::vector<JudgedView>& views, const std::string& command);

}  // namespace ehc_bringup
