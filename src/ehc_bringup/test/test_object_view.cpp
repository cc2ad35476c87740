// The single-view cloud of a library object (objectViewCloud, ehc_object_library cloud): the
// object is settled on the table and seen; the tool's PCD holds the same points; the D400 depth
// model keeps the object's points near its surface at 0.6 m. Objects of both splits, several
// kinds, printed.

#include "ehc_bringup/object_view.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <unistd.h>

namespace {
const std::string kConfig = EHC_CONFIG_DIR;

/// Points of `c` on the object: above the table top and inside its settled bounding sphere.
int objectPoints(const ehc_bringup::ObjectViewCloud& c) {
  const double radius = c.body.halfExtents().norm() + 0.01;
  int n = 0;
  for (const auto& p : c.points)
    n += p.z() > c.table_height + 0.004 && (p.cast<double>() - c.T_world_object.translation()).norm() < radius;
  return n;
}
}  // namespace

TEST(ObjectView, EachObjectRestsOnTheTableAndIsSeen) {
  const ehc_sim::ObjectLibrary lib = ehc_sim::loadObjectLibrary(kConfig + "/objects/library.yaml");
  ehc_sim::SimConfig sim = ehc_sim::loadSimConfig(kConfig + "/sim/bullet_sim.yaml");
  for (const char* name : {"mug_01", "bowl_02", "can_03", "banana_04", "blob_01"}) {
    for (const auto model : {ehc_sim::DepthNoiseModel::Gaussian, ehc_sim::DepthNoiseModel::Stereo}) {
      sim.camera.depth_noise.model = model;
      const ehc_bringup::ObjectViewCloud c = ehc_bringup::objectViewCloud(lib, name, ehc_bringup::ObjectView(), sim, 5);
      const int n = objectPoints(c);
      std::printf("%s (%s), %s depth: %zu points, %d on the object, resting at z %.4f\n", name,
                  lib.object(name).split.c_str(), ehc_sim::toString(model).c_str(), c.points.size(), n,
                  c.T_world_object.translation().z());
      EXPECT_GT(n, 30) << name;
      EXPECT_NEAR(c.T_world_object.translation().z() - c.table_height, c.body.halfExtents().z(), 0.03) << name << " on the table";
    }
  }
}

TEST(ObjectView, TheToolWritesTheSameCloud) {
  const std::string out = "/tmp/ehc_object_view_" + std::to_string(getpid()) + ".pcd";
  const std::string cmd = std::string(EHC_OBJECT_LIBRARY_BIN) + " cloud --object can_02 --seed 3 --out " + out + " > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const ehc_perception::PointList file = ehc_perception::loadPcd(out);
  std::remove(out.c_str());
  const ehc_sim::ObjectLibrary lib = ehc_sim::loadObjectLibrary(kConfig + "/objects/library.yaml");
  const ehc_bringup::ObjectViewCloud c = ehc_bringup::objectViewCloud(
      lib, "can_02", ehc_bringup::ObjectView(), ehc_sim::loadSimConfig(kConfig + "/sim/bullet_sim.yaml"), 3);
  ASSERT_EQ(file.size(), c.points.size());
  for (std::size_t i = 0; i < file.size(); ++i) ASSERT_LT((file[i] - c.points[i]).norm(), 1e-6f);
  EXPECT_NE(std::system((std::string(EHC_OBJECT_LIBRARY_BIN) + " cloud --object no_such --out " + out + " 2> /dev/null").c_str()), 0);
}
