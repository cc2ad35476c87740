#pragma once
// The scene segmentation of tagless targets (GraspGenerator::segmentScene, as
// generateForCloudTarget runs it) checked against the truth (ehc_object_library segment).
//
// Each view is a scene of library objects of one split dropped on the table around a random
// place: the first at a random spot near the table centre, each further one beside a random
// object already placed, their bounding circles (half the bounding box diagonal, any yaw) a gap
// apart drawn in [min_gap, max_gap] and at least min_gap from every other; random yaws. After the
// objects settle, the simulated camera looks at one of them (at random) from a random distance,
// elevation and azimuth (any side). Every point is labelled with the object whose settled
// bounding box (grown by label_margin) holds it.
//
// Per object in the view (at least min_visible_points of its points higher above the table than
// the segmentation keeps): a cluster "holds" it when at least max(min_hold_points, hold_fraction
// x its clustered points) of its points are in the cluster. The outcome:
//   one      one cluster holds it, and nothing else, and spans at least min_extent_ratio of the
//            horizontal extent of its points the segmentation keeps
//   partial  as one, but the cluster spans less (a part of the object was dropped)
//   split    several clusters hold it
//   merged   a cluster holding it holds another object too
//   missed   no cluster holds it
// and what the everyday Exp-2's target selector (nearest to the object's true centre, within
// `radius`) makes of the view: its status, and whether the chosen cluster holds the object.
// ROS-free.

#include "ehc_bringup/object_view.h"
#include "ehc_control/target_selector.h"
#include "ehc_perception/grasp_generator.h"
#include "ehc_sim/object_library.h"
#include "ehc_sim/sim_config.h"

#include <functional>
#include <string>
#include <vector>

namespace ehc_bringup {

enum class SegmentOutcome { One, Partial, Split, Merged, Missed };
std::string toString(SegmentOutcome o);

struct SegmentationCheckParams {
  std::string split = "all";        ///< tuning, validation or all
  std::vector<std::string> kinds;   ///< library kinds drawn from; empty = every kind
  int views = 20;
  unsigned seed = 1;
  int objects = 3;                  ///< per view
  double min_gap = 0.01;            ///< m, bounding circles apart (the everyday Exp-2's minimum)
  double max_gap = 0.03;            ///< m
  double min_distance = 0.4, max_distance = 1.0;             ///< m, camera to the object looked at
  double min_elevation_deg = 10.0, max_elevation_deg = 60.0;  ///< above the table
  double radius = 0.08;             ///< m, the selector's (the everyday Exp-2's library_radius)
  double label_margin = 0.006;      ///< m, bounding boxes grown by this to label points
  int min_visible_points = 10;
  int min_hold_points = 5;
  double hold_fraction = 0.15;
  double min_extent_ratio = 0.7;
  void validate() const;            ///< throws std::invalid_argument "[SegmentationCheck] ..."
};

struct SegmentedObject {
  std::string object, kind;
  int view = 0;
  int points = 0;           ///< its points the segmentation keeps (above the table)
  int clustered = 0;        ///< of them in some cluster
  int holding = 0;          ///< clusters holding it
  double extent_ratio = 0;  ///< horizontal extent of its cluster / of its kept points (one, partial)
  double gap = 0;           ///< m, bounding circles to the nearest other object after settling
  SegmentOutcome outcome = SegmentOutcome::Missed;
  ehc_control::TargetSelectionStatus selection = ehc_control::TargetSelectionStatus::NoObject;
  bool selected_right = false;  ///< selected, and the chosen cluster holds it
};

struct SegmentedView {
  int view = 0;
  ObjectView pose;
  std::string looked_at;
  unsigned noise_seed = 0;
  int clusters = 0;
  std::vector<SegmentedObject> objects;  ///< those visible in the view
};

/// Every view (drawn from the seed sequence (seed, view)); `progress` (if set) after each.
std::vector<SegmentedView> checkSegmentation(const ehc_sim::ObjectLibrary& library, const ehc_sim::SimConfig& sim,
                                             const ehc_perception::GraspGenerator& generator,
                                             const ehc_perception::GraspTargetingParams& targeting,
                                             const SegmentationCheckParams& params,
                                             const std::function<void(const SegmentedView&, int done, int total)>& progress);

/// One CSV line per visible object and view (header first).
std::string segmentationCsv(const std::vector<SegmentedView>& views);
/// Markdown: per kind and in all, the visible objects and each outcome's count, and the
/// selector's statuses.
std::string segmentationSummary(const std::vector<SegmentedView>& views, const std::string& command);

}  // namespace ehc_bringup
