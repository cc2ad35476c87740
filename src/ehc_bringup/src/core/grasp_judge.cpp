#include "ehc_bringup/grasp_judge.h"

#include "ehc_bringup/grasp_selection.h"
#include "ehc_common/enum_names.h"
#include "ehc_common/text_format.h"

#include <BulletCollision/CollisionShapes/btBvhTriangleMeshShape.h>
#include <BulletCollision/CollisionShapes/btTriangleIndexVertexArray.h>
#include <BulletCollision/NarrowPhaseCollision/btRaycastCallback.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/box.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <sstream>
#include <stdexcept>

namespace ehc_bringup {

namespace {

const char* kOwner = "GraspJudge";
constexpr double kDeg = M_PI / 180.0;
constexpr double kOutwardRay = 1.0;  // m, beyond any object's extent

constexpr ehc_common::EnumNames<GraspVerdict, 9> kVerdictNames = {{
    {GraspVerdict::Valid, "valid"},
    {GraspVerdict::NotFinite, "not_finite"},
    {GraspVerdict::ApproachExcluded, "approach_excluded"},
    {GraspVerdict::OutsideOpening, "outside_opening"},
    {GraspVerdict::NothingBetween, "nothing_between"},
    {GraspVerdict::OutsideFrictionCone, "outside_friction_cone"},
    {GraspVerdict::HitsTable, "hits_table"},
    {GraspVerdict::FingerCollides, "finger_collides"},
    {GraspVerdict::PalmCollides, "palm_collides"},
}};

[[noreturn]] void fail(const std::string& what) { throw std::invalid_argument(std::string("[GraspJudge] ") + what); }

/// The closest crossing of a ray (Bullet reports every crossed triangle; keeping the smallest
/// fraction also clips the rest of the traversal). The normal is the triangle's own (unflipped).
struct ClosestCrossing : btTriangleRaycastCallback {
  ClosestCrossing(const btVector3& from, const btVector3& to)
      : btTriangleRaycastCallback(from, to, kF_KeepUnflippedNormal) {}
  btScalar reportHit(const btVector3& normal, btScalar fraction, int /*part*/, int triangle) override {
    if (fraction < best) {
      best = fraction;
      best_normal = normal;
      best_triangle = triangle;
    }
    return fraction;
  }
  btScalar best = 2.0;
  btVector3 best_normal{0, 0, 0};
  int best_triangle = -1;
};

/// A box of `size` centred at `centre` in the grasp frame.
struct GraspBox {
  Eigen::Vector3d centre, size;
};

}  // namespace

std::string toString(GraspVerdict v) { return ehc_common::enumName(kVerdictNames, v, kOwner); }
GraspVerdict graspVerdictFromString(const std::string& s) {
  return ehc_common::enumValue(kVerdictNames, s, kOwner, "grasp verdict");
}

void GraspJudgeParams::validate() const {
  if (!(friction_coefficient > 0.0 && friction_coefficient < 10.0)) fail("friction_coefficient must be in (0, 10)");
  if (!(pregrasp_distance >= 0.0 && pregrasp_distance < 1.0)) fail("pregrasp_distance must be in [0, 1) m");
  if (!(max_approach_tilt_deg > 0.0 && max_approach_tilt_deg <= 180.0)) fail("max_approach_tilt_deg must be in (0, 180]");
  if (!(max_view_angle_deg > 0.0 && max_view_angle_deg <= 180.0)) fail("max_view_angle_deg must be in (0, 180]");
  if (samples < 1 || samples > 1000000) fail("samples must be in [1, 1e6]");
  if (approach_steps < 1 || approach_steps > 360) fail("approach_steps must be in [1, 360]");
  if (accept_checks < 1 || accept_checks > 100000) fail("accept_checks must be in [1, 1e5]");
}

GraspVerdict GraspExistence::commonest() const {
  GraspVerdict best = GraspVerdict::Valid;
  int n = 0;
  for (const auto& [v, count] : verdicts)
    if (v != GraspVerdict::Valid && count > n) {
      best = v;
      n = count;
    }
  return best;
}

struct GraspJudge::Impl {
  ehc_sim::TriangleMesh mesh;
  Eigen::Isometry3d T_world_object, T_object_world;
  std::vector<float> vertices;  // Bullet's copy (single precision, body frame)
  std::vector<int> indices;
  std::unique_ptr<btTriangleIndexVertexArray> bt_array;
  std::unique_ptr<btBvhTriangleMeshShape> bt_shape;
  fcl::BVHModel<fcl::OBBRSSd> fcl_mesh;
  std::vector<double> cumulative_area;  // for sampling surface points by area
};

GraspJudge::GraspJudge(const ehc_sim::TriangleMesh& mesh, const Eigen::Isometry3d& T_world_object, double table_height,
                       const ehc_perception::GripperGeometry& gripper, const GraspJudgeParams& params,
                       const Eigen::Vector3d& view_direction)
    : impl_(new Impl), gripper_(gripper), params_(params), table_height_(table_height) {
  params_.validate();
  if (mesh.empty()) fail("the object's mesh is empty");
  if (!isValidPose(T_world_object) || !std::isfinite(table_height)) fail("the object's pose or the table height is not finite");
  if (!view_direction.allFinite()) fail("the view direction is not finite");
  view_ = view_direction.norm() > 1e-9 ? view_direction.normalized() : Eigen::Vector3d::Zero();
  Impl& m = *impl_;
  m.mesh = mesh;
  m.T_world_object = T_world_object;
  m.T_object_world = T_world_object.inverse();
  for (const Eigen::Vector3d& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) m.vertices.push_back(static_cast<float>(v[k]));
  double area = 0.0;
  std::vector<fcl::Triangle> tris;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) m.indices.push_back(tri[k]);
    tris.emplace_back(tri[0], tri[1], tri[2]);
    const Eigen::Vector3d& a = mesh.vertices[static_cast<std::size_t>(tri[0])];
    area += 0.5 * (mesh.vertices[static_cast<std::size_t>(tri[1])] - a).cross(mesh.vertices[static_cast<std::size_t>(tri[2])] - a).norm();
    m.cumulative_area.push_back(area);
  }
  m.bt_array.reset(new btTriangleIndexVertexArray(static_cast<int>(mesh.triangles.size()), m.indices.data(), 3 * sizeof(int),
                                                  static_cast<int>(mesh.vertices.size()), m.vertices.data(), 3 * sizeof(float)));
  m.bt_shape.reset(new btBvhTriangleMeshShape(m.bt_array.get(), true));
  m.fcl_mesh.beginModel();
  m.fcl_mesh.addSubModel(mesh.vertices, tris);
  m.fcl_mesh.endModel();
}

GraspJudge::~GraspJudge() = default;

bool GraspJudge::firstHit(const Eigen::Vector3d& from, const Eigen::Vector3d& to, Eigen::Vector3d* point,
                          Eigen::Vector3d* normal) const {
  const Eigen::Vector3d a = impl_->T_object_world * from, b = impl_->T_object_world * to;
  const btVector3 ba(static_cast<btScalar>(a.x()), static_cast<btScalar>(a.y()), static_cast<btScalar>(a.z()));
  const btVector3 bb(static_cast<btScalar>(b.x()), static_cast<btScalar>(b.y()), static_cast<btScalar>(b.z()));
  ClosestCrossing cb(ba, bb);
  impl_->bt_shape->performRaycast(&cb, ba, bb);
  if (cb.best_triangle < 0) return false;
  *point = from + static_cast<double>(cb.best) * (to - from);
  // The mesh's own normal (double precision, outward by winding) of the crossed triangle.
  *normal = impl_->T_world_object.linear() * impl_->mesh.normal(static_cast<std::size_t>(cb.best_triangle));
  return true;
}

bool GraspJudge::approachAllowed(const Eigen::Vector3d& approach) const {
  if (approach.dot(-Eigen::Vector3d::UnitZ()) < std::cos(params_.max_approach_tilt_deg * kDeg) - 1e-12) return false;
  if (view_.isZero()) return true;
  return approach.dot(view_) >= std::cos(params_.max_view_angle_deg * kDeg) - 1e-12;
}

GraspVerdict GraspJudge::closingLine(const Eigen::Isometry3d& grasp, GraspJudgement* out) const {
  const double half = 0.5 * gripper_.max_width;
  const Eigen::Vector3d c = grasp.translation(), y = grasp.linear().col(1);
  const double cos_cone = std::cos(std::atan(params_.friction_coefficient));
  bool verdict_cone = false;
  for (int i = 0; i < 2; ++i) {
    const double s = i == 0 ? -1.0 : 1.0;  // the finger on -y, then on +y
    const Eigen::Vector3d dir = -s * y;    // from that finger towards the other
    const Eigen::Vector3d face = c - dir * half;
    Eigen::Vector3d p, n;
    // The finger's inner face inside the object: the line leaves the object first going outwards.
    if (firstHit(face, face - dir * kOutwardRay, &p, &n) && n.dot(dir) < 0.0) return GraspVerdict::OutsideOpening;
    if (!firstHit(face, c + dir * half, &p, &n)) return GraspVerdict::NothingBetween;
    // Entering the object: the outward normal faces the finger (against the ray).
    const double facing = -n.dot(dir);
    if (facing <= 0.0) return GraspVerdict::OutsideOpening;
    out->contact[static_cast<std::size_t>(i)] = p;
    out->contact_angle_deg[static_cast<std::size_t>(i)] = std::acos(std::min(1.0, facing)) / kDeg;
    if (facing < cos_cone) verdict_cone = true;
  }
  out->width = (out->contact[1] - out->contact[0]).dot(y);
  return verdict_cone ? GraspVerdict::OutsideFrictionCone : GraspVerdict::Valid;
}

double GraspJudge::closedWidth(const Eigen::Isometry3d& grasp, double step) const {
  const ehc_perception::GripperGeometry& g = gripper_;
  const double half = 0.5 * g.max_width, z1 = g.finger_tip_depth, z0 = z1 - g.finger_length;
  const int nx = std::max(1, static_cast<int>(std::ceil(g.finger_breadth / step))), nz = std::max(1, static_cast<int>(std::ceil(g.finger_length / step)));
  std::array<double, 2> stop = {{-1.0, -1.0}};  // the nearest crossing's distance from each finger
  for (int i = 0; i < 2; ++i) {
    const double s = i == 0 ? -1.0 : 1.0;
    for (int ix = 0; ix <= nx; ++ix)
      for (int iz = 0; iz <= nz; ++iz) {
        const Eigen::Vector3d face(-0.5 * g.finger_breadth + g.finger_breadth * ix / nx, s * half, z0 + (z1 - z0) * iz / nz);
        Eigen::Vector3d p, n;
        if (!firstHit(grasp * face, grasp * Eigen::Vector3d(face.x(), -face.y(), face.z()), &p, &n)) continue;
        const double d = (p - grasp * face).norm();
        if (stop[static_cast<std::size_t>(i)] < 0.0 || d < stop[static_cast<std::size_t>(i)]) stop[static_cast<std::size_t>(i)] = d;
      }
  }
  if (stop[0] < 0.0 || stop[1] < 0.0) return 0.0;
  return std::max(0.0, g.max_width - stop[0] - stop[1]);
}

GraspVerdict GraspJudge::sweep(const Eigen::Isometry3d& grasp) const {
  const ehc_perception::GripperGeometry& g = gripper_;
  const double d = params_.pregrasp_distance;
  const double z1 = g.finger_tip_depth, z0 = z1 - g.finger_length, zp = z0 - g.palm_height;
  const double yf = 0.5 * g.max_width + 0.5 * g.finger_thickness;
  // The boxes from the pre-grasp (d back along z) to the grasp: fingers, fingers, palm.
  const std::array<GraspBox, 3> boxes = {{
      {{0.0, -yf, 0.5 * (z0 - d + z1)}, {g.finger_breadth, g.finger_thickness, z1 - z0 + d}},
      {{0.0, yf, 0.5 * (z0 - d + z1)}, {g.finger_breadth, g.finger_thickness, z1 - z0 + d}},
      {{0.0, 0.0, 0.5 * (zp - d + z0)}, {g.palm_breadth, g.palm_width, z0 - zp + d}},
  }};
  for (const GraspBox& b : boxes)
    for (int corner = 0; corner < 8; ++corner) {
      const Eigen::Vector3d sign((corner & 1) ? 1.0 : -1.0, (corner & 2) ? 1.0 : -1.0, (corner & 4) ? 1.0 : -1.0);
      if ((grasp * (b.centre + 0.5 * sign.cwiseProduct(b.size))).z() < table_height_) return GraspVerdict::HitsTable;
    }
  fcl::CollisionRequestd request;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const fcl::Boxd box(boxes[i].size);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = boxes[i].centre;
    const fcl::Transform3d T_object_box = impl_->T_object_world * grasp * T;
    fcl::CollisionResultd result;
    fcl::collide(&impl_->fcl_mesh, fcl::Transform3d::Identity(), &box, T_object_box, request, result);
    if (result.isCollision()) return i < 2 ? GraspVerdict::FingerCollides : GraspVerdict::PalmCollides;
  }
  return GraspVerdict::Valid;
}

GraspJudgement GraspJudge::judge(const Eigen::Isometry3d& grasp) const {
  GraspJudgement out;
  if (!isValidPose(grasp)) return out;
  out.verdict = GraspVerdict::ApproachExcluded;
  if (!approachAllowed(grasp.linear().col(2))) return out;
  out.verdict = closingLine(grasp, &out);
  if (out.verdict == GraspVerdict::Valid) out.verdict = sweep(grasp);
  return out;
}

bool GraspJudge::tryAxis(const Eigen::Vector3d& p, const Eigen::Vector3d& y, double phase, const GraspAcceptance& accept,
                         GraspExistence* ex) const {
  // The opposite side: where the ray from p into the object along -y leaves it, within the opening.
  Eigen::Vector3d q, nq;
  const Eigen::Vector3d inside = p - 1e-6 * y;
  if (!firstHit(inside, inside - gripper_.max_width * y, &q, &nq) || nq.dot(y) > 0.0) return false;
  Eigen::Isometry3d grasp = Eigen::Isometry3d::Identity();
  grasp.translation() = 0.5 * (p + q);
  // Evenly spaced approaches around y, and the ones nearest straight down and the view direction.
  std::vector<Eigen::Vector3d> approaches;
  const Eigen::Vector3d e1 = y.unitOrthogonal(), e2 = y.cross(e1);
  for (int k = 0; k < params_.approach_steps; ++k) {
    const double th = phase + 2.0 * M_PI * k / params_.approach_steps;
    approaches.push_back(std::cos(th) * e1 + std::sin(th) * e2);
  }
  for (const Eigen::Vector3d& d : {Eigen::Vector3d(-Eigen::Vector3d::UnitZ()), view_}) {
    const Eigen::Vector3d along = d - d.dot(y) * y;
    if (along.norm() > 1e-6) approaches.push_back(along.normalized());
  }
  for (const Eigen::Vector3d& z : approaches) {
    if (!approachAllowed(z)) continue;
    grasp.linear().col(0) = y.cross(z);
    grasp.linear().col(1) = y;
    grasp.linear().col(2) = z;
    const GraspJudgement j = judge(grasp);
    ++ex->candidates;
    ++ex->verdicts[j.verdict];
    if (!j.valid()) continue;
    if (!accept || accept(grasp)) {
      ex->exists = true;
      ex->grasp = grasp;
      return true;
    }
    if (++ex->refused >= params_.accept_checks) return true;
  }
  return false;
}

GraspExistence GraspJudge::findValidGrasp(unsigned seed, const GraspAcceptance& accept) const {
  const Impl& m = *impl_;
  GraspExistence ex;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double total = m.cumulative_area.back();
  for (int s = 0; s < params_.samples; ++s) {
    const auto it = std::lower_bound(m.cumulative_area.begin(), m.cumulative_area.end(), unit(rng) * total);
    const std::size_t t = std::min<std::size_t>(static_cast<std::size_t>(it - m.cumulative_area.begin()), m.mesh.triangles.size() - 1);
    double u = unit(rng), v = unit(rng);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const double phase = unit(rng) * 2.0 * M_PI / params_.approach_steps;
    const Eigen::Vector3i& tri = m.mesh.triangles[t];
    const Eigen::Vector3d& a = m.mesh.vertices[static_cast<std::size_t>(tri[0])];
    const Eigen::Vector3d local = a + u * (m.mesh.vertices[static_cast<std::size_t>(tri[1])] - a) +
                                  v * (m.mesh.vertices[static_cast<std::size_t>(tri[2])] - a);
    const Eigen::Vector3d n = m.T_world_object.linear() * m.mesh.normal(t);
    if (n.isZero()) continue;
    const Eigen::Vector3d p = m.T_world_object * local;
    // The point's normal, and its horizontal part (closing parallel to the table).
    if (tryAxis(p, n, phase, accept, &ex)) return ex;
    const Eigen::Vector3d level(n.x(), n.y(), 0.0);
    if (level.norm() > 0.1 && std::abs(n.z()) > 1e-6 && tryAxis(p, level.normalized(), phase, accept, &ex)) return ex;
  }
  return ex;
}

ViewJudgement judgeView(const ObjectViewCloud& view, const ehc_perception::GraspGenerator& generator,
                        const ehc_perception::GraspTargetingParams& targeting, const GraspJudgeParams& params,
                        unsigned seed) {
  if (!view.body.mesh) fail("the view's object '" + view.body.name + "' has no mesh");
  const Eigen::Vector3d centre = view.T_world_object.translation(), eye = view.T_world_cam.translation();
  const GraspJudge judge(*view.body.mesh, view.T_world_object, view.table_height, generator.config().gripper, params,
                         centre - eye);
  ViewJudgement out;
  out.existence = judge.findValidGrasp(seed);
  out.result = ehc_perception::generateForTarget(generator, view.points, eye, &centre, targeting);
  const std::vector<ehc_perception::Grasp>& grasps = out.result.grasps;
  if (!grasps.empty()) {
    out.best = judge.judge(grasps.front().pose);
    if (out.best.width > 0.0) out.best.closed_width = judge.closedWidth(grasps.front().pose);
    out.best_any_side = out.best;
    if (out.best.verdict == GraspVerdict::ApproachExcluded)
      out.best_any_side = GraspJudge(*view.body.mesh, view.T_world_object, view.table_height, generator.config().gripper, params)
                              .judge(grasps.front().pose);
  }
  for (std::size_t i = 0; i < std::min<std::size_t>(5, grasps.size()); ++i) {
    if (!(i == 0 ? out.best : judge.judge(grasps[i].pose)).valid()) continue;
    ++out.top5_valid;
    if (out.first_valid_rank == 0) out.first_valid_rank = static_cast<int>(i) + 1;
  }
  out.exists = out.existence.exists || out.top5_valid > 0;
  out.search_missed = !out.existence.exists && out.top5_valid > 0;
  return out;
}

void LibraryJudgeParams::validate() const {
  if (split != "all" && split != "tuning" && split != "validation") fail("split must be tuning, validation or all");
  if (views < 1 || views > 10000) fail("views must be in [1, 10000]");
  if (!(min_distance > 0.1 && max_distance >= min_distance && max_distance < 5.0)) fail("distances must be in (0.1, 5) m, min <= max");
  if (!(min_elevation_deg > 0.0 && max_elevation_deg >= min_elevation_deg && max_elevation_deg < 89.0))
    fail("elevations must be in (0, 89) deg, min <= max");
  judge.validate();
}

std::vector<JudgedView> judgeLibrary(const ehc_sim::ObjectLibrary& library, const ehc_sim::SimConfig& sim,
                                     const ehc_perception::GraspGenerator& generator,
                                     const ehc_perception::GraspTargetingParams& targeting, const LibraryJudgeParams& params,
                                     const std::function<void(const JudgedView&, std::size_t, std::size_t)>& progress) {
  params.validate();
  std::vector<const ehc_sim::LibraryObject*> objects;
  for (const ehc_sim::LibraryObject& o : library.objects)
    if (params.split == "all" || o.split == params.split) objects.push_back(&o);
  const std::size_t total = objects.size() * static_cast<std::size_t>(params.views);
  std::vector<JudgedView> out;
  for (const ehc_sim::LibraryObject* o : objects)
    for (int v = 0; v < params.views; ++v) {
      std::seed_seq seq{params.seed, o->seed, static_cast<unsigned>(v)};
      std::mt19937 rng(seq);
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      JudgedView jv;
      jv.object = o->name;
      jv.kind = o->kind;
      jv.split = o->split;
      jv.view = v;
      jv.pose.distance = params.min_distance + unit(rng) * (params.max_distance - params.min_distance);
      jv.pose.elevation_deg = params.min_elevation_deg + unit(rng) * (params.max_elevation_deg - params.min_elevation_deg);
      jv.pose.azimuth_deg = -180.0 + 360.0 * unit(rng);
      jv.noise_seed = static_cast<unsigned>(rng() % 1000000000u);
      const unsigned search_seed = static_cast<unsigned>(rng());
      const ObjectViewCloud cloud = objectViewCloud(library, o->name, jv.pose, sim, jv.noise_seed);
      jv.judgement = judgeView(cloud, generator, targeting, params.judge, search_seed);
      out.push_back(jv);
      if (progress) progress(out.back(), out.size(), total);
    }
  return out;
}

namespace {

using ehc_common::fixedDecimals;


std::string percent(int n, int of) { return of > 0 ? fixedDecimals(100.0 * n / of, 0) + " %" : "-"; }

}  // namespace

std::string judgedViewsCsv(const std::vector<JudgedView>& views) {
  std::ostringstream f;
  f << "object,kind,split,view,distance,elevation_deg,azimuth_deg,noise_seed,exists,search_missed,candidates_judged,no_grasp_verdict,"
       "generator_status,generator_reason,grasps,best_valid,best_verdict,best_verdict_any_side,best_measured_width_mm,best_true_width_mm,best_closed_width_mm,"
       "best_contact_angle_deg,best_seen_contacts,top5_valid,first_valid_rank\n";
  for (const JudgedView& v : views) {
    const ViewJudgement& j = v.judgement;
    const bool any = !j.result.grasps.empty();
    f << v.object << "," << v.kind << "," << v.split << "," << v.view << "," << fixedDecimals(v.pose.distance, 3) << ","
      << fixedDecimals(v.pose.elevation_deg, 1) << "," << fixedDecimals(v.pose.azimuth_deg, 1) << "," << v.noise_seed << ","
      << (j.exists ? 1 : 0) << "," << (j.search_missed ? 1 : 0) << "," << j.existence.candidates << ","
      << (j.exists ? "" : toString(j.existence.commonest())) << "," << ehc_perception::toString(j.result.failure) << ","
      << ehc_common::csvField(j.result.reason) << "," << j.result.grasps.size() << ",";
    if (any) {
      const ehc_perception::Grasp& g = j.result.grasps.front();
      const double angle = std::max(j.best.contact_angle_deg[0], j.best.contact_angle_deg[1]);
      f << (j.best.valid() ? 1 : 0) << "," << toString(j.best.verdict) << "," << toString(j.best_any_side.verdict) << ","
        << fixedDecimals(1e3 * g.measured_width, 1) << ","
        << (j.best.width > 0.0 ? fixedDecimals(1e3 * j.best.width, 1) : "") << ","
        << (j.best.closed_width > 0.0 ? fixedDecimals(1e3 * j.best.closed_width, 1) : "") << "," << (angle >= 0.0 ? fixedDecimals(angle, 1) : "") << ","
        << g.seen_contacts << ",";
    } else {
      f << ",,,,,,,,";
    }
    f << j.top5_valid << "," << j.first_valid_rank << "\n";
  }
  return f.str();
}

namespace {

/// The summary table's row of one split.
std::string summaryRow(const std::string& split, const std::vector<JudgedView>& views) {
  int n = 0, exists = 0, best = 0, any_side = 0, top5 = 0, none_proposed = 0, none = 0, no_grasp = 0, missed = 0;
  for (const JudgedView& v : views) {
    if (split != "all" && v.split != split) continue;
    const ViewJudgement& j = v.judgement;
    ++n;
    missed += j.search_missed;
    if (j.exists) {
      ++exists;
      best += j.best.valid();
      any_side += j.best_any_side.valid();
      top5 += j.top5_valid > 0;
      no_grasp += j.result.grasps.empty();
    } else {
      ++none;
      none_proposed += !j.result.grasps.empty();
    }
  }
  if (n == 0) return "";
  return "| " + split + " | " + std::to_string(n) + " | " + std::to_string(exists) + " | " + std::to_string(best) + " (" +
         percent(best, exists) + ") | " + std::to_string(any_side) + " | " + std::to_string(top5) + " (" + percent(top5, exists) + ") | " +
         std::to_string(no_grasp) + " | " + std::to_string(none) + " | " + std::to_string(none_proposed) + " | " +
         std::to_string(missed) + " |\n";
}

/// Counts of the best grasps' verdicts and the generator's failures, per split.
std::string verdictTable(const std::vector<JudgedView>& views) {
  std::map<std::string, std::map<std::string, int>> counts;  // split -> "what" -> views
  for (const JudgedView& v : views) {
    const ViewJudgement& j = v.judgement;
    const std::string what = j.result.grasps.empty() ? "no grasp: " + ehc_perception::toString(j.result.failure)
                                                     : "best grasp: " + toString(j.best.verdict);
    ++counts[v.split][std::string(j.exists ? "exists, " : "none exists, ") + what];
  }
  std::string s = "| split | view | outcome | views |\n|---|---|---|---|\n";
  for (const auto& [split, m] : counts)
    for (const auto& [what, count] : m) {
      const std::size_t comma = what.find(", ");
      s += "| " + split + " | " + what.substr(0, comma) + " | " + what.substr(comma + 2) + " | " + std::to_string(count) + " |\n";
    }
  return s;
}

}  // namespace

std::string judgedViewsSummary(const std::vector<JudgedView>& views, const std::string& command) {
  std::string s = "# Grasps on the object library judged against the true meshes\n\n`" + command + "`\n\n";
  s += "A valid grasp: approach allowed, both contacts on the closing line inside the opening, contact normals in the "
       "friction cone, fingers and palm swept in from the pre-grasp without touching the object or the table "
       "(ehc_bringup/grasp_judge.h).\n\n";
  s += "A valid grasp exists in a view where the search on the true mesh finds one or one of the generator's top five "
       "is valid (search missed: only the latter). Valid best grasp, valid in top 5 and no grasp proposed count the views "
       "where one exists; from any side: the best grasp valid without the view rule (approaching from any side).\n\n";
  s += "| split | views | a valid grasp exists | valid best grasp | ... from any side | valid in top 5 | no grasp proposed | "
       "none exists | grasp proposed where none exists | search missed |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const char* split : {"tuning", "validation", "all"}) s += summaryRow(split, views);
  s += "\n" + verdictTable(views);
  return s;
}

}  // namespace ehc_bringup
