#include "ehc_bringup/object_view.h"

#include "ehc_control/pose_math.h"
#include "ehc_control/robot_config.h"
#include "ehc_sim/sim_world.h"
#include "ehc_sim/simulated_camera.h"

#include <cmath>
#include <stdexcept>

namespace ehc_bringup {

SceneViewCloud sceneViewCloud(const ehc_sim::ObjectLibrary& library, const std::vector<ObjectPlacement>& placements,
                              std::size_t look_at, const ObjectView& view, const ehc_sim::SimConfig& sim, unsigned seed) {
  if (look_at >= placements.size())
    throw std::invalid_argument("[ObjectView] the camera looks at object " + std::to_string(look_at) + " of " +
                                std::to_string(placements.size()));
  SceneViewCloud out;
  ehc_sim::SceneConfig scene;
  scene.name = "object_view";
  scene.source_file = library.source_file;
  ehc_sim::TableConfig table;
  table.name = "table";
  scene.tables.push_back(table);
  out.table_height = table.height;
  for (const ObjectPlacement& p : placements) {
    ehc_sim::BodyConfig body = ehc_sim::libraryBody(library, p.name);
    body.position = Eigen::Vector3d(p.x, p.y, table.height + body.halfExtents().z() + 0.002);
    body.rpy = Eigen::Vector3d(0.0, 0.0, p.yaw);
    scene.objects.push_back(body);
    out.bodies.push_back(body);
  }
  ehc_sim::SimConfig cfg = sim;
  cfg.fake_robot.seed = seed;
  const ehc_control::RobotConfig robot = ehc_control::loadRobotConfig(cfg.fake_robot.robot_file);
  ehc_sim::SimWorld world(cfg, robot, scene);
  const Eigen::VectorXd still = Eigen::VectorXd::Zero(world.robot().nDof());
  while (world.time() < 1.0) world.step(still);
  for (std::size_t i = 0; i < placements.size(); ++i) out.T_world_objects.push_back(world.objectPose(static_cast<int>(i)));
  const Eigen::Vector3d centre = out.T_world_objects[look_at].translation();
  const double el = view.elevation_deg * M_PI / 180.0, az = view.azimuth_deg * M_PI / 180.0;
  const Eigen::Vector3d eye =
      centre + view.distance * Eigen::Vector3d(-std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  out.T_world_cam = ehc_control::lookAt(eye, centre);
  ehc_sim::SimulatedCamera camera(ehc_control::loadPinholeCamera(ehc_sim::simCameraFile(cfg, robot)), cfg.camera, seed);
  std::vector<Eigen::Vector3f> cam_points;
  camera.cloud(world, out.T_world_cam, &cam_points);
  const Eigen::Isometry3f T = out.T_world_cam.cast<float>();
  out.points.reserve(cam_points.size());
  for (const auto& p : cam_points) out.points.push_back(T * p);
  return out;
}

ObjectViewCloud objectViewCloud(const ehc_sim::ObjectLibrary& library, const std::string& name, const ObjectView& view,
                                const ehc_sim::SimConfig& sim, unsigned seed) {
  ObjectPlacement place;
  place.name = name;
  SceneViewCloud s = sceneViewCloud(library, {place}, 0, view, sim, seed);
  ObjectViewCloud out;
  out.points = std::move(s.points);
  out.T_world_cam = s.T_world_cam;
  out.T_world_object = s.T_world_objects.front();
  out.body = s.bodies.front();
  out.table_height = s.table_height;
  return out;
}

}  // namespace ehc_bringup
