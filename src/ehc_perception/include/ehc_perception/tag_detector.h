#pragma once
// TagDetector: AprilTag detection and pose in the camera optical frame, wrapping ViSP
// vpDetectorAprilTag. Tag size (edge of the black square, metres) per id from YAML.
// Tag frame (ViSP / AprilTag convention): origin at the tag centre, x right, y up (as the tag
// is printed), z out of the printed face; a tag facing the camera squarely has
// T_cam_tag.rotation() == diag(1, -1, -1).
// Planar-pose ambiguity: a small or distant tag seen obliquely has two poses, tilted one way or
// the other about the line of sight, that reproject equally well (a 21 px tag 1.1 m away, 19 deg
// oblique: both within 1e-3 px, 35 deg apart). ViSP returns both (getPose's second solution);
// when they reproject within `ambiguity_margin` px of each other the detector keeps the one
// consistent with a world prior (default: the tag is printed upright, its y axis points up),
// given the camera's pose in the world at the image's time (detect(image, T_world_cam)).
// Tracking window (roi_margin > 0): after an image in which tags were found, the next image is
// searched only in the box around them (around the wanted tags when some are wanted: other tags
// are found again in the next whole image), grown by the margin; every roi_full_frame_every-th
// image is searched whole (new tags are found then). The image after one in which a wanted tag
// (setWantedTags: the target) was not found is searched whole, unless the camera's world pose is
// given (detect(image, T_world_cam)) and every wanted tag has been seen before: then the window is
// the box around where those tags were last seen in the world, projected into this image (grown
// the same way), and when none of them can be in view (not whole in the image grown by
// roi_margin, a corner behind the camera, or its printed face turned away) the image is not
// searched at all until the next whole one. So a target that is hidden, out of view or lost costs
// a window or nothing per image instead of a whole search, and a target that moved while unseen
// is found again within roi_full_frame_every images. Why: the search's cost grows with the area searched, and pixel noise in flat regions
// makes it costly (2 grey levels of i.i.d. noise, the simulator's: 57 ms instead of 4 ms a 640x480
// frame, see bench_perception), more than a 15 Hz stream allows. The window follows the tags from
// image to image: successive images must come from one camera stream (a jump costs one image).
// ROS-free; not thread-safe (the ViSP detector and the window keep state).

#include "ehc_control/pinhole_camera.h"

#include <Eigen/Geometry>
#include <visp3/core/vpImage.h>

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

class vpCameraParameters;

namespace ehc_common {
class ConfigNode;
}  // namespace ehc_common

namespace ehc_perception {

struct TagDetectorConfig {
  std::string family = "36h11";           ///< 36h11 | 25h9 | 16h5
  double default_tag_size = 0.05;          ///< m, black-square edge, for ids not in tag_sizes
  std::map<int, double> tag_sizes;         ///< m, per tag id
  double quad_decimate = 1.0;              ///< >= 1; 2 is faster, less range
  int threads = 1;                         ///< AprilTag worker threads
  /// px: tracking window (see above) = the box around the (wanted) tags found in the previous image,
  /// grown on every side by this plus half the box's own size; 0 = search every image whole.
  int roi_margin = 0;
  /// Every this-many images one is searched whole even while tracking (>= 1; 1 = every image).
  int roi_full_frame_every = 5;
  /// px (0 = off): in a window, quads are found on the image decimated by the largest whole
  /// factor (at most 4, at least quad_decimate) that keeps the expected tag's side at least this
  /// long; the tag is decoded and its corners refined on the full image. A close tag (100 px and
  /// more) costs a quarter of the search or less.
  double roi_decimated_tag_px = 0.0;
  std::string pose_method = "homography_virtual_vs";  ///< see poseMethodNames()
  double max_reprojection_error = 2.0;     ///< px (RMS); detections above are dropped
  /// Pose prior for ambiguous detections: the tag axis `prior_tag_axis` (tag frame) points as
  /// close as possible to `prior_world_direction` (world frame). Default: tags printed upright
  /// on a vertical face (the pattern's top, tag y, is the world's up), as in every scene.
  Eigen::Vector3d prior_tag_axis = Eigen::Vector3d::UnitY();
  Eigen::Vector3d prior_world_direction = Eigen::Vector3d::UnitZ();
  /// px (RMS): the two pose solutions are ambiguous when their reprojection errors differ by at
  /// most this; then the prior decides (0: never, the lower error always wins).
  double ambiguity_margin = 0.5;

  double tagSize(int id) const;
  void validate() const;  ///< throws std::invalid_argument "[TagDetector] ..."
  std::string summary() const;
  static std::vector<std::string> familyNames();
  static std::vector<std::string> poseMethodNames();
};

/// Reads a `tag_detector` mapping (every field optional, defaults above) and validates it.
TagDetectorConfig loadTagDetectorConfig(const ehc_common::ConfigNode& node);

struct TagDetection {
  int id = -1;
  double tag_size = 0.0;                            ///< m, the size used for the pose
  Eigen::Isometry3d T_cam_tag = Eigen::Isometry3d::Identity();
  std::array<Eigen::Vector2d, 4> corners;           ///< px, ViSP polygon order
  double reprojection_error = 0.0;                  ///< px, RMS over the 4 corners
  /// The other planar-pose solution (not kept) and its RMS reprojection error (px); equal to
  /// T_cam_tag / reprojection_error when ViSP found only one.
  Eigen::Isometry3d T_cam_tag_other = Eigen::Isometry3d::Identity();
  double other_reprojection_error = 0.0;
  /// The two solutions were within ambiguity_margin: the prior chose (or, without a camera
  /// pose, the lower error did).
  bool ambiguous = false;
};

class TagDetector {
 public:
  /// Throws std::invalid_argument on a bad config or camera.
  TagDetector(const TagDetectorConfig& config, const ehc_control::PinholeCamera& camera);
  ~TagDetector();
  TagDetector(TagDetector&&) noexcept;
  TagDetector& operator=(TagDetector&&) noexcept;

  /// Detects every tag of the family. The image must have the camera's size (throws
  /// std::invalid_argument otherwise). Distortion is ignored (pass rectified images).
  std::vector<TagDetection> detect(const vpImage<unsigned char>& gray);
  /// Same, resolving ambiguous poses with the configured prior: `T_world_cam` is the camera's
  /// (optical frame's) pose in the world at the image's time. Throws on a non-finite pose.
  std::vector<TagDetection> detect(const vpImage<unsigned char>& gray,
                                   const Eigen::Isometry3d& T_world_cam);
  /// Same as detect(gray), from a raw 8-bit grey buffer (`stride` bytes per row).
  std::vector<TagDetection> detect(const unsigned char* data, int width, int height, int stride);

  /// Tags the caller needs (its targets; default none): while one of them is missing from an
  /// image's detections, the next image is searched whole. A change of the set also makes the
  /// next image a whole one.
  void setWantedTags(const std::vector<int>& ids);
  /// Forgets the tracking window: the next image is searched whole, or where the wanted tags
  /// were last seen (see above).
  void resetTracking();
  /// Images searched whole / in a window (tracking or predicted) / not searched because no
  /// wanted tag could be in view, since construction.
  long fullFrameSearches() const { return full_searches_; }
  long windowSearches() const { return window_searches_; }
  long skippedSearches() const { return skipped_searches_; }

  const TagDetectorConfig& config() const { return config_; }
  const ehc_control::PinholeCamera& camera() const { return camera_; }

 private:
  /// Where the wanted tags can be in the next image, from their last world poses.
  enum class Prediction { Unknown, InView, OutOfView };
  /// A predicted corner nearer than this (m) to the camera plane: the tag cannot be in view.
  static constexpr double kMinPredictionDepth = 0.02;
  /// `T_world_cam`: the camera's world pose at the image's time (the ambiguity prior and the
  /// predicted window), or null.
  std::vector<TagDetection> detectResolving(const vpImage<unsigned char>& gray, const Eigen::Isometry3d* T_world_cam);
  /// Runs ViSP on the whole image or on the window (false: nothing found, or not searched);
  /// `u0`, `v0`: the searched region's top-left pixel, `cam`: its camera.
  bool search(const vpImage<unsigned char>& gray, const Eigen::Isometry3d* T_world_cam, int* u0, int* v0,
              const vpCameraParameters** cam);
  /// The window (InView) around the wanted tags' last world poses seen from T_world_cam, and the
  /// shortest side (px) of those tags in it.
  Prediction predict(const Eigen::Isometry3d& T_world_cam, std::array<int, 4>* window, double* tag_px) const;
  /// The box [lo, hi] (px) grown by roi_margin + half its size, clipped to the image; width 0
  /// when less than 16 px of it is inside.
  std::array<int, 4> windowAround(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi) const;
  /// Sets the next image's tracking window from this image's detections.
  void track(const std::vector<TagDetection>& found);
  struct Impl;
  TagDetectorConfig config_;
  ehc_control::PinholeCamera camera_;
  std::unique_ptr<Impl> impl_;
  /// Tracking window for the next image: column, row of its top-left pixel, width, height;
  /// width 0 = search the next image whole.
  std::array<int, 4> window_{{0, 0, 0, 0}};
  double window_tag_px_ = 0.0;  ///< the shortest side (px) of the tags the window was set around
  int images_since_full_ = 0;
  std::vector<int> wanted_tags_;
  std::map<int, Eigen::Isometry3d> seen_in_world_;  ///< tag id -> its last pose found with a camera pose
  long full_searches_ = 0, window_searches_ = 0, skipped_searches_ = 0;
};

/// Reads a PNG / PGM / PPM / JPEG file as 8-bit grey (ViSP vpImageIo).
/// Throws std::invalid_argument "[TagDetector] cannot read image '<path>': ...".
vpImage<unsigned char> loadGrayImage(const std::string& path);

/// The object to reach: a tag id and the fixed pose of the target (grasp) frame in the tag
/// frame, T_tag_target (the "grasp offset").
struct TagTargetConfig {
  int tag_id = 0;
  Eigen::Vector3d offset_xyz = Eigen::Vector3d::Zero();  ///< m, in the tag frame
  Eigen::Vector3d offset_rpy = Eigen::Vector3d::Zero();  ///< rad, fixed-axis roll-pitch-yaw

  Eigen::Isometry3d offset() const;
  void validate() const;  ///< throws std::invalid_argument "[TagTarget] ..."
  std::string summary() const;
};
TagTargetConfig loadTagTargetConfig(const ehc_common::ConfigNode& node);

/// T_cam_target = T_cam_tag * T_tag_target for the configured tag; false if it is not among
/// the detections.
bool findTarget(const std::vector<TagDetection>& detections, const TagTargetConfig& target,
                Eigen::Isometry3d* T_cam_target);
/// The target in the world: T_world_cam * findTarget's T_cam_target (ehc_tag_node with tf at the
/// image stamp, the in-process pipeline with the simulated camera pose). false if the tag is not
/// among the detections; throws std::runtime_error "[TagTarget] ..." for a non-finite result.
bool findTargetInWorld(const std::vector<TagDetection>& detections, const TagTargetConfig& target,
                       const Eigen::Isometry3d& T_world_cam, Eigen::Isometry3d* T_world_target);

/// Roll-pitch-yaw (fixed axes X, Y, Z as in URDF) to a rotation matrix.
Eigen::Matrix3d rpyToMatrix(const Eigen::Vector3d& rpy);

}  // namespace ehc_perception
