#pragma once
// GraspGenerator: parallel-jaw grasps from a point cloud (PCL inside, not in this header).
//
// Object cloud -> voxel filter -> normals -> antipodal contact pairs (friction cone) ->
// approach directions around each closing axis -> reject grasps whose fingers or palm hit the
// cloud or the support plane, or that need more than the gripper's opening -> GS-Net*-style
// score -> non-maximum suppression -> refinement (centred on the object, then pushed as deep
// as collision-free) -> non-maximum suppression again -> best first.
// Scene clouds: the support plane is removed with RANSAC and the objects Euclidean-clustered.
//
// Score (GS-Net*, paper section IV-B): antipodal quality x centre-of-gravity weight (the
// approach line should pass through the object's centroid: weight from the angle between the
// approach direction and the direction from the gripper's approach origin to the centroid)
// x PCA weight (finger closing axis, and approach axis, aligned with the object's principal
// axes). Refinement: the grasp is centred between the object's measured sides along the
// closing axis and moved along the finger breadth axis onto the object's middle: on a support,
// across the footprint's narrow side the completed footprint's centre and along its long side
// the centroid (one view's centroid lies towards the camera, where it shows the most surface;
// along its length it is the centre of mass), a round body's axis or a ball's centre.
// Depth refinement: the contact pairs give a grasp centre near the contacts, often close to
// an edge (e.g. just below the top face of a standing box, fingers overlapping the object by
// ~2 cm). The grasp is then pushed forward along its approach axis (z) in steps of
// depth_step, up to max_depth_shift, re-running the same finger / palm / width / support
// check at each step; the search stops at the first step that fails (palm reaching the
// object's top, fingertips reaching support_clearance above the support, ...). When a step
// failed on the cloud, the grasp is backed off by depth_margin from the deepest passing step
// (never behind its original depth), so depth noise does not bring the palm onto the object:
// the gripper then keeps at least ~depth_margin from whatever stopped it. A step stopped by the
// support alone (support_clearance; the plane is fitted on many points) is not backed off: the
// last step is halved twice, so an object lower than the fingers is closed on near its middle
// height. When no step failed (max_depth_shift reached) there is no back-off. Refined grasps are rescored, and as
// several candidates can converge onto the same deep pose, suppressed again.
//
// Single-view clouds of objects on a support. Besides the antipodal pairs and
// the single-contact hypotheses, the closing axes parallel to the support along the object's
// footprint (its points projected onto the support; least-area rectangle) are hypotheses of
// quality footprint_weight: for a convex object the extreme points along such an axis carry it
// as their normal, so they are an antipodal pair even where one contact is not seen. This is
// what finds the grasp across a lying cylinder, whose sides a single view shows only at grazing
// angles (no antipodal pair there, the seeds' normals tilted up). The object's extent across a
// closing axis counts the unseen volume below the seen points down to the support, and round
// sections are completed by a fitted circle (round_fit_tolerance): a cylinder lying across the
// axis (circle resting on the support; the section within a finger's breadth of the object's
// middle along its length, where the fingers close, so that a bent body such as a banana is not
// smeared into no circle at all) or standing (circular footprint of its mantle; the points
// inside the circle by more than the tolerance, a narrower section such as a bottle's shoulder,
// are left out of its fit, and a circle more than 1.25 x the seen footprint's longer side is an
// arc of something else, e.g. a banana's bent side); an upright round object's circle bounds
// every hypothesis closing parallel to the support through its middle half.
//
// Measured width (robust estimates, not extreme points): each side of the object between the
// fingers is its contact surface fitted by least squares: the object's points in the fingers'
// slab whose estimated normal (oriented outwards, see below) lies within the
// friction cone (atan(friction_coefficient)) of the closing axis, near that side's trimmed
// extreme (4 x the cloud's noise + 2 voxels), at least min_contact_points of them, fitted with
// y = a + b x + c x^2 + d z + e z^2 over the finger's breadth (x) and length (z) and refitted
// without the points beyond 3 RMS; the side is where that surface reaches farthest, counting
// only significant terms (a crest, the outer end of a slope, else the patch's mean). A side
// without such a patch is not seen by the view: it is bounded by a fitted completion (the
// circle of a round section, standing or lying, or the sphere of a ball, whose RMS is within
// round_fit_tolerance beyond the cloud's noise and whose points cover an arc of 60 deg), else
// by the trimmed extreme of the points between the fingers and, for single-contact and
// footprint hypotheses, of the object's extent (its points and their projections onto the
// support); the last samples of a surface that runs on under a finger or past it (each within
// two sample spacings and the noise of the one before; a bar lying along the closing axis) bound
// the side where they end. Grasps with an unseen side rank below seen ones (antipodal quality at
// most single_contact_weight). The cloud's noise is estimated from the normals' plane fits.
//
// Outward normals: away from the object's centroid (convex objects); with the viewpoint known
// (hidden_volume_check) and a single view (at most a quarter of the points more than the hidden
// volume's margin behind the nearest point along their ray), towards the camera, where every
// surface a view shows faces, except within 15 deg of perpendicular to the ray (grazing: the
// centroid decides). One view of a box shows mostly one face and its centroid lies near that
// face, which the centroid alone turned partly inwards (a "contact pair" 3-5 mm apart on one
// face); a part of a non-convex object facing the rest (one bar of a cross) faces the centroid.
//
// Margin rule (gripper.clearance): a grasp needs  measured width + 2 x clearance <= max_width.
// With the 70 mm gripper and clearance 0.5 mm, objects measured up to 69 mm are grasped.
// test_grasp_widths prints the widths measured on the simulator's single views (3 views x 2
// noise seeds); when no grasp is found and the footprint's narrowest completed width breaks
// the rule, the reason is "too wide: the object measures W m across its narrowest axis
// parallel to the support; the gripper opens 0.07 m and needs C m clearance each side
// (objects up to X m)" and the failure GraspFailure::TooWide.
//
// Slanted contacts: a side without a contact patch in the friction cone whose outermost points
// face the finger within slanted_contact_deg (a face tilted from the closing axis), or whose
// fitted surface's normal at the contact is outside the cone, is a seen contact that slips: the
// pose is refused (friction). A face running along the closing axis (a top face up to its
// unseen far edge) leaves the side unseen.
//
// Hidden volume (hidden_volume_check; the viewpoint given to generate is the camera's origin):
// along the rays from the camera, the space behind the object's points facing the camera and
// not in front of a point facing away (clouds seen from several sides). A finger at a seen
// contact, or at a contact pair's side bounded only by its last samples, and the palm's face
// must stay out of it (3 x 5 and 3 x 3 samples, a quarter tolerated); a finger at an unseen
// side of a single-contact or footprint hypothesis is in it by construction and ranks lower.
//
// Wall grasps (wall_weight; the viewpoint known): one finger on a seen surface facing
// horizontally, the other beyond the object's far side at the nearest position where neither
// the finger nor its path in may lie behind a seen point along the camera's rays: the width is
// bounded by what the view proves, never assumed (a bowl's rim, whose wall a view never shows
// from both sides, is grasped across the wall and the shadow behind it). Centred on the wall's
// middle where the view shows its top between the fingers (as near as the opening allows), so
// that the symmetric close reaches both faces together. One contact is seen: they rank with the
// single-contact hypotheses. Each is approached straight down and, with wall_tilt_deg, also
// tilted about its closing axis towards the viewpoint's side: the fingers stay on the wall's two
// faces and the wrist comes back towards the robot (an arm mounted below the support's top
// reaches no straight-down rim grasp a quarter of a metre or more beyond the support's edge).
//
// No grasp: the failure is what refused the best-ranked pose that held enough of the object
// (too wide, friction, collides, hidden volume), the reason counts every check's refusals; an
// object whose footprint breaks the margin rule is too wide, with the sentence below.
//
// Grasp frame: origin between the fingertips at the grasp centre, z = approach direction
// (into the object), y = finger closing direction, x = y cross z.
// All geometry is in the cloud's frame; `up` (config) is the gravity-up direction there.

#include "ehc_control/target_selector.h"
#include "ehc_perception/object_extent.h"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_perception {

using PointList = std::vector<Eigen::Vector3f>;

struct GripperGeometry {
  double max_width = 0.070;         ///< m, maximum opening
  double finger_length = 0.050;     ///< m, along the approach axis
  double finger_tip_depth = 0.010;  ///< m, fingertips reach this far beyond the grasp origin
  double finger_thickness = 0.010;  ///< m, along the closing axis
  double finger_breadth = 0.020;    ///< m, along the grasp x axis
  double palm_height = 0.080;       ///< m, gripper body behind the fingers (along approach)
  double palm_width = 0.110;        ///< m, along the closing axis
  double palm_breadth = 0.060;      ///< m, along x
  /// m, margin each side of the measured width (the margin rule: measured width + 2 x
  /// clearance <= max_width; see the header comment)
  double clearance = 0.0005;
};

struct GraspGeneratorConfig {
  GripperGeometry gripper;
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();  ///< gravity up in the cloud frame
  double voxel_size = 0.004;          ///< m, voxel filter leaf
  double normal_radius = 0.012;       ///< m, normal estimation radius
  int min_object_points = 30;         ///< after filtering; fewer => no grasp
  /// After filtering, at most this many points per object: beyond it the voxel edge grows until
  /// they fit (every part of the object keeps points, coarser), which bounds the work per object
  /// whatever the cloud. 5000 points at 4 mm are 0.08 m^2 of surface, far more than any object
  /// the gripper can close around shows; only larger clusters are coarsened.
  int max_object_points = 5000;
  int max_seeds = 200;                ///< contact points sampled
  int pairs_per_seed = 2;             ///< antipodal partners kept per seed
  int approach_steps = 16;            ///< approach directions around each closing axis
  /// Coulomb friction coefficient mu of the finger pads on objects: a contact holds if its
  /// surface normal is within the friction cone, atan(mu) of the closing axis (0.36: 19.8 deg).
  /// Contact pairs, the fitted contact surfaces' normals and the measured contacts are checked
  /// against it.
  double friction_coefficient = 0.36;
  /// deg: a side whose contact patch is not within the friction cone but whose outermost
  /// points' normals are within this angle of the closing axis is a contact the view shows at
  /// a slant: the finger would slip, the grasp is refused (a face running along the closing
  /// axis, e.g. a top face up to its unseen far edge, is beyond it: that side is unseen).
  double slanted_contact_deg = 65.0;
  /// Fingers at seen contacts and the palm must stay out of the volume the view hides behind
  /// the object's points (seen from the viewpoint given to generate, the camera's origin); off
  /// when the cloud's viewpoint is not known.
  bool hidden_volume_check = true;
  /// max angle between the approach and straight down, and (the viewpoint known: with
  /// hidden_volume_check) between the approach and the view direction (camera to centroid)
  double max_approach_tilt_deg = 95.0;
  int max_collision_points = 2;       ///< cloud points tolerated inside fingers/palm (noise)
  double outlier_fraction = 0.03;     ///< ... or this fraction of the points there, if more
  /// Object points needed between the fingers, at the voxel grid's density: a cloud sparser than
  /// voxel_size (its median nearest-neighbour spacing s, e.g. a small object far from a coarse
  /// camera) needs the same surface in fewer points: min_points x (voxel_size / s)^2, at least 3.
  int min_points_between_fingers = 10;
  double support_clearance = 0.005;   ///< m, gripper must stay this far above the support
  bool assume_support_below = true;   ///< object clouds: support plane at the lowest point
  double approach_standoff = 0.10;    ///< m, approach origin behind the grasp (centroid angle)
  double centroid_sigma_deg = 10.0;   ///< width of the centroid-angle weight
  double pca_power = 8.0;             ///< exponent of the closing-axis PCA alignment
  double pca_approach_power = 2.0;    ///< exponent of the approach-axis PCA alignment
  double pca_isotropy_ratio = 0.85;   ///< principal axes with std-dev ratio above: one subspace
  double max_refine_shift = 0.04;     ///< m, largest move of the refinement step
  /// m, largest push of the grasp along its approach axis (depth refinement); 0 disables.
  double max_depth_shift = 0.04;
  double depth_step = 0.005;          ///< m, step of the depth search (> 0 if enabled)
  /// m, back-off from the deepest collision-free step when a deeper step collided (never
  /// behind the original depth); < max_depth_shift.
  double depth_margin = 0.005;
  /// Collision checks per object at most (candidates are checked best first); bounds the
  /// time on objects where most candidates fail. A hypothesis whose fitted completion (circle,
  /// sphere) is wider than the opening is refused once, its approaches unchecked and not counted.
  int max_evaluations = 800;
  /// Antipodal quality given to single-contact hypotheses (closing axis = the seed's normal,
  /// far side unseen, as in one-view clouds); 0 disables them.
  double single_contact_weight = 0.7;
  /// Antipodal quality given to footprint hypotheses (object on a support: closing axes
  /// parallel to it along the footprint's least-area rectangle, width = the object's extent
  /// across them); 0 disables them.
  double footprint_weight = 1.0;
  /// Antipodal quality at most of wall grasps (a seen contact facing horizontally, the other
  /// finger beyond the object's far side where the view proves there is nothing, closing across
  /// a rim, a wall or a thin part; see wall_grasps.h), times the seen contact's normal cosine; 0
  /// disables them. Needs the viewpoint (hidden_volume_check) and a support.
  double wall_weight = 0.6;
  /// deg in [0, 80]: wall grasps also with the approach turned by this from straight down about
  /// the closing axis, its horizontal part away from the viewpoint (the hand from the camera's
  /// side; checked as the straight-down ones are, in the tilted frame); 0: straight down only.
  double wall_tilt_deg = 45.0;
  /// m, RMS distance within which a footprint axis's cross-section counts as round (a circle
  /// tangent to the support, e.g. a lying cylinder): its circle then gives the width across
  /// that axis where the single view sees the sides only at grazing angles.
  double round_fit_tolerance = 0.002;
  /// Points a contact surface's fit needs on one side of the closing axis (the points between
  /// the fingers whose estimated normal is within the friction cone of the closing axis, near
  /// that side's outermost points); with fewer the side counts as unseen.
  int min_contact_points = 6;
  double nms_distance = 0.01;         ///< m, grasps closer than this and ...
  double nms_angle_deg = 20.0;        ///< ... this rotation are duplicates
  int top_k = 10;                     ///< grasps returned per object
  unsigned seed = 1;                  ///< sampling seed (deterministic)
  // Scene segmentation (support plane + clusters).
  double plane_distance = 0.008;      ///< m, RANSAC inlier distance
  double plane_max_tilt_deg = 15.0;   ///< plane normal vs up
  double min_plane_fraction = 0.2;    ///< plane inliers / points to accept a support plane
  double cluster_tolerance = 0.015;   ///< m, Euclidean clustering distance (at least)
  /// With a viewpoint, a point's clustering distance grows to this x the cloud's angular point
  /// pitch x its range (a far surface is sampled sparsely); 0 keeps cluster_tolerance.
  double cluster_spacing_factor = 3.0;
  /// m, clusters whose footprints on the support (convex hulls) overlap or are closer than this
  /// are one object (a bowl's near and far walls); below the gap between neighbouring objects.
  /// Negative: no merging.
  double footprint_merge_gap = 0.005;
  double max_object_extent = 0.35;    ///< m, a merge never makes a footprint wider than this
  int min_cluster_points = 30;        ///< points of an object (after merging)
  int max_objects = 10;

  void validate() const;  ///< throws std::invalid_argument "[GraspGenerator] ..."
  std::string summary() const;
};

/// Reads a `grasp_generator` mapping (all fields optional; gripper: sub-mapping).
GraspGeneratorConfig loadGraspGeneratorConfig(const ehc_common::ConfigNode& node);

/// Why a generator call gave no grasp (one string map: toString / graspFailureFromString).
enum class GraspFailure {
  None,              ///< there are grasps
  EmptyCloud,        ///< no points
  NoFinitePoints,    ///< every point NaN / Inf
  BadViewpoint,      ///< the viewpoint is not finite
  TooFewPoints,      ///< fewer than min_object_points after the voxel filter
  BadSupportPlane,   ///< the given support plane is not finite
  NoObject,          ///< scenes: nothing above the support plane, or no cluster
  TooWide,           ///< the object is wider than the opening across every closing axis tried
  NoAntipodalPair,   ///< no contact pair within the friction cone and the opening
  Collides,          ///< every candidate collides with the cloud or the support, or does not fit
  Friction,          ///< every fitting candidate touches a seen surface outside the friction cone
  HiddenVolume,      ///< every fitting candidate puts a finger or the palm in the volume hidden behind the view
  TargetTooFar,      ///< generateForTarget: the nearest object is outside the target gate
};
std::string toString(GraspFailure f);
GraspFailure graspFailureFromString(const std::string& s);  ///< throws "[GraspGenerator] unknown ..."

struct Grasp {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();  ///< grasp frame in the cloud frame
  double width = 0.0;            ///< m, opening needed (measured width + 2 x clearance)
  /// m, the object's width between the fingers: the distance between the two contact surfaces
  /// fitted along the closing axis (see the header comment); width - 2 x clearance.
  double measured_width = 0.0;
  /// Contacts the view supports (0, 1 or 2): sides whose contact surface was fitted from the
  /// points between the fingers. An unseen side is bounded by the object's extent or its fitted
  /// circle / sphere; such grasps rank below fully supported ones (single_contact_weight).
  int seen_contacts = 0;
  /// A wall grasp (wall_weight): its unseen side bounded by the view's shadow, approached
  /// straight down or tilted about the closing axis (wall_tilt_deg).
  bool wall = false;
  double score = 0.0;            ///< antipodal x centroid x pca, in [0, 1]
  double antipodal = 0.0;        ///< min |cos| between contact normals and closing axis
  double centroid_weight = 0.0;
  double pca_weight = 0.0;
  int object = 0;                ///< index of the object (scene mode), else 0
};

struct GraspResult {
  std::vector<Grasp> grasps;     ///< best first
  std::string reason;            ///< why there is no grasp ("" when there are grasps)
  GraspFailure failure = GraspFailure::None;  ///< the reason's kind
  int objects = 0;               ///< objects considered
  std::vector<Eigen::Vector3d> centroids;  ///< per object
  bool support_plane_found = false;
  Eigen::Vector4d support_plane = Eigen::Vector4d::Zero();  ///< n.p + d = 0, n = up side
  int input_points = 0, finite_points = 0;
  /// generateForTarget: points left by the point budget (GraspTargetingParams::max_input_points).
  int budget_points = 0;
  /// Points of the object(s) after the voxel filter (each object at most max_object_points).
  int filtered_points = 0;
  double voxel_size = 0.0;  ///< m, the largest voxel edge used (voxel_size, grown for a large object)
};

struct SceneSegmentation {
  bool plane_found = false;
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  ///< n.p + d = 0, n towards up
  std::vector<PointList> objects;                   ///< largest first
  PointList obstacles;                              ///< every point above the plane
  std::string reason;
  GraspFailure failure = GraspFailure::None;
  /// The mean of objects[i]'s points.
  Eigen::Vector3d centroid(std::size_t i) const;
  /// The index of the object whose centroid is nearest `p`; -1 when there is none.
  int nearestObject(const Eigen::Vector3d& p) const;
};

class GraspGenerator {
 public:
  explicit GraspGenerator(const GraspGeneratorConfig& config);  ///< validates
  ~GraspGenerator();

  /// Grasps on one object. `support_plane` (n.p + d = 0, n up) if known; otherwise the
  /// lowest point along `up` if assume_support_below. `collision_cloud`: extra points the
  /// gripper must not hit (e.g. the other objects). Never throws on bad clouds: empty /
  /// non-finite / too small inputs give no grasp and a `reason`.
  GraspResult generate(const PointList& object, const Eigen::Vector3d& viewpoint,
                       const Eigen::Vector4d* support_plane = nullptr,
                       const PointList* collision_cloud = nullptr) const;

  /// Removes the support plane (RANSAC, normal within plane_max_tilt_deg of up) and clusters
  /// the rest: connected within cluster_tolerance (with `viewpoint`, grown with the range by
  /// cluster_spacing_factor), parts whose footprints on the support overlap merged (see
  /// footprint_merge_gap). Without a plane, the whole finite cloud is clustered. With `near`
  /// (where the target is), the plane is the one under it (at most max_object_extent below),
  /// not a larger one farther down (the floor seen past a table's edge); where the view has
  /// planes but none under it, no object ("no support plane under the target").
  SceneSegmentation segmentScene(const PointList& scene, const Eigen::Vector3d* viewpoint = nullptr,
                                 const Eigen::Vector3d* near = nullptr) const;

  /// segmentScene + generateFromSegmentation.
  GraspResult generateFromScene(const PointList& scene, const Eigen::Vector3d& viewpoint,
                                const Eigen::Vector3d* near = nullptr) const;
  /// generate per object of a segmented scene (the other objects are collision geometry), merged
  /// best first. With `near`, only the object whose centroid is closest to it is used.
  GraspResult generateFromSegmentation(const SceneSegmentation& seg, const Eigen::Vector3d& viewpoint,
                                       const Eigen::Vector3d* near = nullptr) const;

  const GraspGeneratorConfig& config() const { return config_; }

 private:
  GraspGeneratorConfig config_;
};

/// How ehc_grasp_node works through its clouds and aims the grasps at the perceived target
/// object (its `node` section; the in-process experiment pipeline reads the same fields of the
/// same file).
struct GraspTargetingParams {
  double max_rate_hz = 2.0;     ///< clouds processed per second at most
  /// At most this many points of a cloud are read (point_cloud_layout.h PointBudget), before
  /// anything else: an organised cloud on an even grid of its rows and columns. A 640x480 D435
  /// frame is read every 4th row and column (19 200 points, 6 mm apart at 0.5 m, under the
  /// simulator's 12 mm on its 80x60 ray grid, on which the grasps are tested); the work per cloud
  /// does not grow with its size.
  int max_input_points = 20000;
  double target_timeout = 2.0;  ///< s; an older target is ignored (grasps for every object)
  double target_gate = 0.15;    ///< m; no grasps if the nearest object is farther from the target
  void validate() const;        ///< throws std::invalid_argument "[GraspTargeting] ..."
  std::string summary() const;
};
/// Reads max_rate_hz, max_input_points, target_timeout and target_gate of a `node` mapping (all
/// optional).
GraspTargetingParams loadGraspTargetingParams(const ehc_common::ConfigNode& node);

/// At most targeting.max_input_points of `scene` (budgetPoints; the node reads a message within
/// the same budget), generateFromScene near `target` (every object without one), then the gate:
/// if the nearest object's centroid is farther than target_gate from the target there are no
/// grasps (the reason says how far). What ehc_grasp_node and the in-process pipeline do with
/// each cloud.
GraspResult generateForTarget(const GraspGenerator& generator, const PointList& scene,
                              const Eigen::Vector3d& viewpoint, const Eigen::Vector3d* target,
                              const GraspTargetingParams& targeting);

/// A target without a tag (ehc_control::TargetSelector, a cloud kind) in one cloud: the object
/// the selector names, or the one tracked so far, and its grasps.
struct CloudTargetResult {
  /// Selected: `centre` is the target's cloud centre (its cluster's centroid); else why there is
  /// no target (no object, too few, ambiguous, the tracked object gone).
  ehc_control::TargetSelection selection;
  GraspResult grasps;  ///< generateForTarget on the target (empty without one)
  /// The cloud's segmentation (within the point budget) the target was found in and its grasps
  /// generated from; `object` is the target's cluster in it (-1 without a target).
  SceneSegmentation segmentation;
  int object = -1;
};
/// The cloud (within the point budget) is segmented once. With `tracked` (the target's pose so
/// far, e.g. the sequencer's filtered pose): on the support under it, the target is the object
/// nearest it (within target_gate). Without: the selector picks among the objects' centroids as
/// seen from `camera` (ehc_control::selectTarget, up = the generator's; a `nearest` target on the
/// support under its point). Then the grasps of that object as generateForTarget makes them.
/// A target that runs out of the camera's frame (a point of its cluster within 1.5 pixel pitches
/// of the edge of the frame the scene's points span, in `camera`'s optical frame) keeps only the
/// grasps with both contacts seen: the object's extent, the last samples and the view's shadow
/// that bound an unseen side stop at the frame, the object does not (failure HiddenVolume when
/// none is left). What ehc_grasp_node and the in-process pipeline do for a cloud target.
CloudTargetResult generateForCloudTarget(const GraspGenerator& generator, const PointList& scene,
                                         const Eigen::Isometry3d& camera, const ehc_control::TargetSelector& selector,
                                         const Eigen::Vector3d* tracked, const GraspTargetingParams& targeting);
/// The extent of a cloud target's cluster (clusterExtent from `viewpoint`, down to the support plane
/// of its segmentation); nullopt without a target.
std::optional<ObjectExtent> cloudTargetExtent(const CloudTargetResult& r, const Eigen::Vector3d& viewpoint,
                                              const Eigen::Vector3d& up);

/// PCD files (PCL). loadPcd reads x, y, z of any point type; throws std::invalid_argument
/// "[PointCloudIO] cannot read '<path>' ..." on a missing or malformed file.
PointList loadPcd(const std::string& path);
void savePcd(const std::string& path, const PointList& points);  ///< binary PCD

}  // namespace ehc_perception
