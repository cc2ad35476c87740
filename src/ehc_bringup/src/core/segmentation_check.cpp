#include "ehc_bringup/segmentation_check.h"

#include "ehc_common/config_node.h"
#include "ehc_common/enum_names.h"
#include "ehc_perception/point_cloud_layout.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_bringup {

namespace {

constexpr ehc_common::EnumNames<SegmentOutcome, 5> kOutcomeNames = {{
    {SegmentOutcome::One, "one"},
    {SegmentOutcome::Partial, "partial"},
    {SegmentOutcome::Split, "split"},
    {SegmentOutcome::Merged, "merged"},
    {SegmentOutcome::Missed, "missed"},
}};

void bad(const std::string& what) { throw std::invalid_argument("[SegmentationCheck] " + what); }

/// Bounding circle radius of a library object on the table (any yaw).
double footprint(const ehc_sim::LibraryObject& o) { return 0.5 * std::hypot(o.size.x(), o.size.y()); }

/// The view's objects and where they are dropped (see the header); empty if no draw of 1000 fits
/// the table.
std::vector<ObjectPlacement> drawPlacements(const std::vector<const ehc_sim::LibraryObject*>& pool,
                                            const SegmentationCheckParams& p, std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const ehc_sim::TableConfig table;
  for (int attempt = 0; attempt < 1000; ++attempt) {
    std::vector<const ehc_sim::LibraryObject*> chosen = pool;
    std::shuffle(chosen.begin(), chosen.end(), *rng);
    chosen.resize(static_cast<std::size_t>(p.objects));
    std::vector<ObjectPlacement> out;
    bool fits = true;
    for (std::size_t i = 0; i < chosen.size() && fits; ++i) {
      ObjectPlacement o;
      o.name = chosen[i]->name;
      o.yaw = -M_PI + 2.0 * M_PI * unit(*rng);
      if (i == 0) {
        o.x = table.center.x() + 0.2 * (unit(*rng) - 0.5);
        o.y = table.center.y() + 0.4 * (unit(*rng) - 0.5);
      } else {
        const std::size_t k = static_cast<std::size_t>(unit(*rng) * static_cast<double>(i)) % i;
        const double d = footprint(*chosen[k]) + footprint(*chosen[i]) + p.min_gap + (p.max_gap - p.min_gap) * unit(*rng);
        const double a = 2.0 * M_PI * unit(*rng);
        o.x = out[k].x + d * std::cos(a);
        o.y = out[k].y + d * std::sin(a);
      }
      const double r = footprint(*chosen[i]);
      fits = std::abs(o.x - table.center.x()) + r < 0.5 * table.size.x() - 0.02 &&
             std::abs(o.y - table.center.y()) + r < 0.5 * table.size.y() - 0.02;
      for (std::size_t j = 0; j < i && fits; ++j)
        fits = std::hypot(o.x - out[j].x, o.y - out[j].y) >= r + footprint(*chosen[j]) + p.min_gap - 1e-9;
      out.push_back(o);
    }
    if (fits) return out;
  }
  return {};
}

/// Horizontal extent: the largest distance between two of the points projected along `up`.
double horizontalExtent(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& up) {
  double best = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i)
    for (std::size_t j = i + 1; j < pts.size(); ++j) {
      const Eigen::Vector3d d = pts[i] - pts[j];
      best = std::max(best, (d - d.dot(up) * up).norm());
    }
  return best;
}

/// The index of the object whose grown bounding box holds `p` (the nearest centre of several), -1 none.
int labelOf(const Eigen::Vector3d& p, const SceneViewCloud& scene, double margin) {
  int best = -1;
  double best_d = 1e9;
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) {
    const Eigen::Vector3d local = scene.T_world_objects[i].inverse() * p;
    if ((local.cwiseAbs() - scene.bodies[i].halfExtents()).maxCoeff() > margin) continue;
    if (local.norm() < best_d) best_d = local.norm(), best = static_cast<int>(i);
  }
  return best;
}

SegmentedView scoreView(const SceneViewCloud& scene, const ehc_perception::SceneSegmentation& seg,
                        const std::vector<const ehc_sim::LibraryObject*>& objects, const SegmentationCheckParams& p,
                        const ehc_perception::GraspGeneratorConfig& gen) {
  const std::size_t n = objects.size();
  const Eigen::Vector3d up = gen.up.normalized();
  const double keep = 1.5 * gen.plane_distance;
  SegmentedView v;
  v.clusters = static_cast<int>(seg.objects.size());
  // Kept points per object (truth), and per cluster the points of each object.
  std::vector<std::vector<Eigen::Vector3d>> kept(n);
  for (const auto& q : scene.points) {
    const Eigen::Vector3d x = q.cast<double>();
    if (!x.allFinite() || x.z() - scene.table_height <= keep) continue;
    const int l = labelOf(x, scene, p.label_margin);
    if (l >= 0) kept[static_cast<std::size_t>(l)].push_back(x);
  }
  std::vector<std::vector<int>> count(seg.objects.size(), std::vector<int>(n, 0));
  std::vector<Eigen::Vector3d> centres;
  for (std::size_t c = 0; c < seg.objects.size(); ++c) {
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (const auto& q : seg.objects[c]) {
      m += q.cast<double>();
      const int l = labelOf(q.cast<double>(), scene, p.label_margin);
      if (l >= 0) ++count[c][static_cast<std::size_t>(l)];
    }
    centres.push_back(m / static_cast<double>(std::max<std::size_t>(1, seg.objects[c].size())));
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (static_cast<int>(kept[i].size()) < p.min_visible_points) continue;
    SegmentedObject o;
    o.object = objects[i]->name;
    o.kind = objects[i]->kind;
    o.points = static_cast<int>(kept[i].size());
    o.gap = 1e9;
    for (std::size_t j = 0; j < n; ++j)
      if (j != i)
        o.gap = std::min(o.gap, (scene.T_world_objects[i].translation() - scene.T_world_objects[j].translation()).head<2>().norm() -
                                    footprint(*objects[i]) - footprint(*objects[j]));
    for (std::size_t c = 0; c < count.size(); ++c) o.clustered += count[c][i];
    const auto holds = [&](std::size_t c, std::size_t j) {
      int all = 0;
      for (std::size_t k = 0; k < count.size(); ++k) all += count[k][j];
      return count[c][j] >= std::max<double>(p.min_hold_points, p.hold_fraction * all);
    };
    int holder = -1;
    bool merged = false;
    for (std::size_t c = 0; c < count.size(); ++c) {
      if (!holds(c, i)) continue;
      ++o.holding;
      holder = static_cast<int>(c);
      for (std::size_t j = 0; j < n; ++j) merged = merged || (j != i && holds(c, j));
    }
    if (o.holding == 0) o.outcome = SegmentOutcome::Missed;
    else if (merged) o.outcome = SegmentOutcome::Merged;
    else if (o.holding > 1) o.outcome = SegmentOutcome::Split;
    else {
      std::vector<Eigen::Vector3d> mine;
      for (const auto& q : seg.objects[static_cast<std::size_t>(holder)]) mine.push_back(q.cast<double>());
      const double truth = horizontalExtent(kept[i], up);
      o.extent_ratio = truth > 0.0 ? horizontalExtent(mine, up) / truth : 1.0;
      o.outcome = o.extent_ratio >= p.min_extent_ratio ? SegmentOutcome::One : SegmentOutcome::Partial;
    }
    ehc_control::TargetSelector s;
    s.kind = ehc_control::TargetSelectorKind::Nearest;
    s.point = scene.T_world_objects[i].translation();
    s.radius = p.radius;
    const ehc_control::TargetSelection sel = ehc_control::selectTarget(s, centres, scene.T_world_cam, up);
    o.selection = sel.status;
    o.selected_right = sel.selected() && holds(static_cast<std::size_t>(sel.index), i);
    v.objects.push_back(o);
  }
  return v;
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

}  // namespace

std::string toString(SegmentOutcome o) { return ehc_common::enumName(kOutcomeNames, o, "SegmentationCheck"); }

void SegmentationCheckParams::validate() const {
  if (split != "all" && split != "tuning" && split != "validation") bad("split must be all, tuning or validation (is '" + split + "')");
  ehc_common::requireRange("SegmentationCheck", "views", views, 1, 1000000);
  ehc_common::requireRange("SegmentationCheck", "objects", objects, 1, 10);
  ehc_common::requireRange("SegmentationCheck", "min_gap", min_gap, 0.0, 0.5);
  ehc_common::requireRange("SegmentationCheck", "max_gap", max_gap, min_gap, 0.5);
  ehc_common::requireRange("SegmentationCheck", "min_distance", min_distance, 0.2, 3.0);
  ehc_common::requireRange("SegmentationCheck", "max_distance", max_distance, min_distance, 3.0);
  ehc_common::requireRange("SegmentationCheck", "min_elevation_deg", min_elevation_deg, 1.0, 89.0);
  ehc_common::requireRange("SegmentationCheck", "max_elevation_deg", max_elevation_deg, min_elevation_deg, 89.0);
  ehc_common::requireRange("SegmentationCheck", "radius", radius, 0.0, 10.0);
}

std::vector<SegmentedView> checkSegmentation(const ehc_sim::ObjectLibrary& library, const ehc_sim::SimConfig& sim,
                                             const ehc_perception::GraspGenerator& generator,
                                             const ehc_perception::GraspTargetingParams& targeting,
                                             const SegmentationCheckParams& params,
                                             const std::function<void(const SegmentedView&, int, int)>& progress) {
  params.validate();
  std::vector<const ehc_sim::LibraryObject*> pool;
  for (const ehc_sim::LibraryObject& o : library.objects)
    if ((params.split == "all" || o.split == params.split) &&
        (params.kinds.empty() || std::find(params.kinds.begin(), params.kinds.end(), o.kind) != params.kinds.end()))
      pool.push_back(&o);
  if (static_cast<int>(pool.size()) < params.objects)
    bad("the library has " + std::to_string(pool.size()) + " object(s) of that split and kinds, a view needs " +
        std::to_string(params.objects));
  std::vector<SegmentedView> out;
  for (int v = 0; v < params.views; ++v) {
    std::seed_seq seq{params.seed, static_cast<unsigned>(v)};
    std::mt19937 rng(seq);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const std::vector<ObjectPlacement> places = drawPlacements(pool, params, &rng);
    if (places.empty()) bad("no placement of " + std::to_string(params.objects) + " objects fits the table");
    ObjectView pose;
    pose.distance = params.min_distance + unit(rng) * (params.max_distance - params.min_distance);
    pose.elevation_deg = params.min_elevation_deg + unit(rng) * (params.max_elevation_deg - params.min_elevation_deg);
    pose.azimuth_deg = -180.0 + 360.0 * unit(rng);
    const std::size_t look = static_cast<std::size_t>(unit(rng) * static_cast<double>(places.size())) % places.size();
    const unsigned noise_seed = static_cast<unsigned>(rng() % 1000000000u);
    const SceneViewCloud scene = sceneViewCloud(library, places, look, pose, sim, noise_seed);
    // As generateForCloudTarget segments a cloud: within the point budget.
    const auto budget = static_cast<std::size_t>(targeting.max_input_points);
    const Eigen::Vector3d eye = scene.T_world_cam.translation();
    const ehc_perception::SceneSegmentation seg = generator.segmentScene(
        scene.points.size() > budget ? ehc_perception::budgetPoints(scene.points, budget) : scene.points, &eye);
    std::vector<const ehc_sim::LibraryObject*> objects;
    for (const ObjectPlacement& pl : places) objects.push_back(&library.object(pl.name));
    SegmentedView sv = scoreView(scene, seg, objects, params, generator.config());
    sv.view = v;
    sv.pose = pose;
    sv.looked_at = places[look].name;
    sv.noise_seed = noise_seed;
    for (SegmentedObject& o : sv.objects) o.view = v;
    out.push_back(sv);
    if (progress) progress(out.back(), v + 1, params.views);
  }
  return out;
}

std::string segmentationCsv(const std::vector<SegmentedView>& views) {
  std::ostringstream f;
  f << "view,object,kind,looked_at,distance,elevation_deg,azimuth_deg,noise_seed,clusters,gap_m,points,clustered,holding,"
       "extent_ratio,outcome,selection,selected_right\n";
  for (const SegmentedView& v : views)
    for (const SegmentedObject& o : v.objects)
      f << v.view << "," << o.object << "," << o.kind << "," << v.looked_at << "," << fixed(v.pose.distance, 3) << ","
        << fixed(v.pose.elevation_deg, 1) << "," << fixed(v.pose.azimuth_deg, 1) << "," << v.noise_seed << "," << v.clusters
        << "," << fixed(o.gap, 4) << "," << o.points << "," << o.clustered << "," << o.holding << ","
        << fixed(o.extent_ratio, 2) << "," << toString(o.outcome) << "," << ehc_control::toString(o.selection) << ","
        << (o.selected_right ? 1 : 0) << "\n";
  return f.str();
}

std::string segmentationSummary(const std::vector<SegmentedView>& views, const std::string& command) {
  struct Row {
    int objects = 0, right = 0;
    std::map<SegmentOutcome, int> outcome;
    std::map<ehc_control::TargetSelectionStatus, int> selection;
  };
  std::map<std::string, Row> rows;
  for (const SegmentedView& v : views)
    for (const SegmentedObject& o : v.objects)
      for (const std::string& k : {o.kind, std::string("all")}) {
        Row& r = rows[k];
        ++r.objects;
        ++r.outcome[o.outcome];
        ++r.selection[o.selection];
        r.right += o.selected_right ? 1 : 0;
      }
  using S = ehc_control::TargetSelectionStatus;
  std::ostringstream md;
  md << "# Scene segmentation against the truth\n\n`" << command << "`: " << views.size()
     << " views; per kind, the objects in view and how the segmentation took them (one cluster per object, "
        "see ehc_bringup/segmentation_check.h), and the target selector's status (nearest to the object's centre).\n\n"
     << "| kind | objects | one | partial | split | merged | missed | selected right | ambiguous | no object |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (auto& [kind, r] : rows)
    md << "| " << kind << " | " << r.objects << " | " << r.outcome[SegmentOutcome::One] << " | "
       << r.outcome[SegmentOutcome::Partial] << " | " << r.outcome[SegmentOutcome::Split] << " | "
       << r.outcome[SegmentOutcome::Merged] << " | " << r.outcome[SegmentOutcome::Missed] << " | " << r.right << " | "
       << r.selection[S::Ambiguous] << " | " << r.selection[S::NoObject] << " |\n";
  return md.str();
}

}  // namespace ehc_bringup
