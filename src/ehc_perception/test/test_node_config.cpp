// The perception nodes' configurations (node_config.h): defaults, validation errors naming the
// file and the field, unknown keys rejected, and every shipped node config loads.
#include "ehc_perception/node_config.h"
#include "ehc_test/perception_fixtures.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>
#include <unistd.h>

namespace ehc_perception {
namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = "/tmp/ehc_perception_test_" + std::to_string(::getpid()) + "_" + name;
  std::ofstream(path) << text;
  return path;
}

/// The message of the std::invalid_argument `f` throws ("" if it throws none).
std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

/// `f` throws an error that names `file` and every one of `words` (the field, the owner).
void expectError(const std::function<void()>& f, const std::string& file, const std::vector<std::string>& words) {
  const std::string e = errorOf(f);
  ASSERT_FALSE(e.empty()) << "no error (expected one naming " << words.front() << ")";
  EXPECT_NE(e.find(file), std::string::npos) << e;
  for (const std::string& w : words) EXPECT_NE(e.find(w), std::string::npos) << "'" << w << "' not in: " << e;
}

const std::string kObstacleNode = "node: {robot_config: realman_rm65_water2}\n";

// ---------------------------------------------------------------- defaults

TEST(NodeConfig, AnEmptyTagNodeFileGivesTheDefaults) {
  const TagNodeConfig c = loadTagNodeConfig(writeTemp("tag_empty.yaml", "{}\n"));
  const TagNodeConfig d;
  EXPECT_EQ(c.image_topic, "/camera/color/image_raw");
  EXPECT_EQ(c.camera_info_topic, "/camera/color/camera_info");
  EXPECT_EQ(c.target_topic, "/ehc/target_pose");
  EXPECT_EQ(c.world_frame, "odom");
  EXPECT_EQ(c.camera_frame, "");
  EXPECT_EQ(c.camera_file, "");
  EXPECT_EQ(c.tf_timeout, 0.05);
  EXPECT_EQ(c.stale_after, 0.5);
  EXPECT_EQ(c.max_image_pixels, 1920 * 1080);
  EXPECT_EQ(c.summary(), d.summary());  // the detector and the target too
  EXPECT_NO_THROW(d.validate());
}

TEST(NodeConfig, AnEmptyGraspNodeFileGivesTheDefaults) {
  const GraspNodeConfig c = loadGraspNodeConfig(writeTemp("grasp_empty.yaml", "{}\n"));
  EXPECT_EQ(c.cloud_topic, "/camera/depth/points");
  EXPECT_EQ(c.target_topic, "/ehc/target_pose");
  EXPECT_EQ(c.output_topic, "/ehc/grasp_candidates");
  EXPECT_EQ(c.world_frame, "odom");
  EXPECT_EQ(c.targeting.max_rate_hz, 2.0);
  EXPECT_EQ(c.targeting.target_timeout, 2.0);
  EXPECT_EQ(c.targeting.target_gate, 0.15);
  EXPECT_EQ(c.targeting.max_input_points, 20000);
  EXPECT_EQ(c.tf_timeout, 0.1);
  EXPECT_EQ(c.stale_after, 0.5);
  EXPECT_EQ(c.generator.max_object_points, 5000);
  EXPECT_EQ(c.summary(), GraspNodeConfig().summary());  // the generator too
  EXPECT_NO_THROW(GraspNodeConfig().validate());
}

TEST(NodeConfig, AnObstacleNodeFileWithOnlyTheRobotGivesTheDefaults) {
  const ObstacleNodeConfig c = loadObstacleNodeConfig(writeTemp("obstacle_min.yaml", kObstacleNode));
  EXPECT_TRUE(std::filesystem::equivalent(c.robot_config, test::robotYaml())) << c.robot_config;  // name -> robot.yaml
  EXPECT_EQ(c.cloud_topic, "/camera/depth/points");
  EXPECT_EQ(c.joint_states_topic, "/joint_states");
  EXPECT_EQ(c.odom_topic, "/odom");
  EXPECT_EQ(c.output_topic, "/ehc/obstacles");
  EXPECT_EQ(c.exclusion_topic, "/ehc/obstacle_exclusion");
  EXPECT_EQ(c.world_frame, "odom");
  EXPECT_EQ(c.publish_rate_hz, 50.0);
  EXPECT_EQ(c.tf_timeout, 0.05);
  EXPECT_EQ(c.stale_after, 0.2);
  EXPECT_EQ(c.monitor.max_input_points, 80000);
  ObstacleNodeConfig d;
  d.robot_config = c.robot_config;
  EXPECT_EQ(c.summary(), d.summary());  // the monitor and the map too
  EXPECT_NO_THROW(d.validate());
}

// ---------------------------------------------------------------- values read

TEST(NodeConfig, FieldsAreReadAndTheCameraFileIsRelativeToTheConfig) {
  const std::string tag = writeTemp("tag_fields.yaml",
                                    "node: {image_topic: /img, camera_info_topic: '', camera_file: cam.yaml,\n"
                                    "       target_topic: /t, world_frame: map, camera_frame: cam, tf_timeout: 0.5,\n"
                                    "       stale_after: 0.3, max_image_pixels: 307200}\n"
                                    "tag_detector: {family: 25h9}\n"
                                    "target: {tag_id: 3}\n");
  const TagNodeConfig c = loadTagNodeConfig(tag);
  EXPECT_EQ(c.image_topic, "/img");
  EXPECT_EQ(c.camera_file, "/tmp/cam.yaml");
  EXPECT_EQ(c.target_topic, "/t");
  EXPECT_EQ(c.world_frame, "map");
  EXPECT_EQ(c.camera_frame, "cam");
  EXPECT_EQ(c.tf_timeout, 0.5);
  EXPECT_EQ(c.stale_after, 0.3);
  EXPECT_EQ(c.max_image_pixels, 307200);
  EXPECT_EQ(c.detector.family, "25h9");
  EXPECT_EQ(c.target.tag_id, 3);

  const GraspNodeConfig g = loadGraspNodeConfig(writeTemp(
      "grasp_fields.yaml", "node: {target_topic: '', max_rate_hz: 5, target_timeout: 0.5, stale_after: 0.7,\n"
                           "       max_input_points: 5000}\n"
                           "grasp_generator: {top_k: 4, max_object_points: 900}\n"));
  EXPECT_EQ(g.target_topic, "");
  EXPECT_EQ(g.targeting.max_rate_hz, 5.0);
  EXPECT_EQ(g.targeting.target_timeout, 0.5);
  EXPECT_EQ(g.stale_after, 0.7);
  EXPECT_EQ(g.targeting.max_input_points, 5000);
  EXPECT_EQ(g.generator.top_k, 4);
  EXPECT_EQ(g.generator.max_object_points, 900);

  const ObstacleNodeConfig o = loadObstacleNodeConfig(writeTemp(
      "obstacle_fields.yaml", "node: {robot_config: kuka_iiwa14_kmr, exclusion_topic: '', publish_rate_hz: 20,\n"
                              "       state_timeout: 0.3, stale_after: 0.4, max_input_points: 1000}\n"
                              "obstacle_map: {resolution: 0.05}\n"));
  EXPECT_NE(o.robot_config.find("kuka_iiwa14_kmr"), std::string::npos) << o.robot_config;
  EXPECT_EQ(o.exclusion_topic, "");
  EXPECT_EQ(o.publish_rate_hz, 20.0);
  EXPECT_EQ(o.monitor.state_timeout, 0.3);
  EXPECT_EQ(o.stale_after, 0.4);
  EXPECT_EQ(o.monitor.max_input_points, 1000);
  EXPECT_EQ(o.map.resolution, 0.05);
}

TEST(NodeConfig, LockstepInputsAreTheSubscribedTopicsAndTf) {
  TagNodeConfig t;
  EXPECT_EQ(t.lockstepInputs(),
            (std::vector<std::string>{"/camera/color/image_raw", "/tf", "/camera/color/camera_info"}));
  t.camera_file = "/x/camera.yaml";  // no camera_info topic then
  EXPECT_EQ(t.lockstepInputs(), (std::vector<std::string>{"/camera/color/image_raw", "/tf"}));

  GraspNodeConfig g;
  EXPECT_EQ(g.lockstepInputs(), (std::vector<std::string>{"/camera/depth/points", "/ehc/target_pose", "/tf"}));
  g.target_topic.clear();
  EXPECT_EQ(g.lockstepInputs(), (std::vector<std::string>{"/camera/depth/points", "/tf"}));

  ObstacleNodeConfig o;
  EXPECT_EQ(o.lockstepInputs(), (std::vector<std::string>{"/camera/depth/points", "/joint_states", "/odom", "/tf",
                                                          "/ehc/obstacle_exclusion"}));
  o.exclusion_topic.clear();
  EXPECT_EQ(o.lockstepInputs(), (std::vector<std::string>{"/camera/depth/points", "/joint_states", "/odom", "/tf"}));
}

// ---------------------------------------------------------------- errors

TEST(NodeConfig, ABadValueNamesTheFileAndTheField) {
  auto tag = [](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    const std::string path = writeTemp(name, text);
    expectError([&] { loadTagNodeConfig(path); }, path, words);
  };
  tag("tag_tf.yaml", "node: {tf_timeout: 9}\n", {"TagNodeConfig", "node.tf_timeout"});
  tag("tag_stale.yaml", "node: {stale_after: 0}\n", {"TagNodeConfig", "node.stale_after"});
  tag("tag_pixels.yaml", "node: {max_image_pixels: 0}\n", {"TagNodeConfig", "node.max_image_pixels"});
  tag("tag_queue.yaml", "node: {image_queue: 5}\n", {"unknown field 'node.image_queue'"});  // the newest image only
  tag("tag_frame.yaml", "node: {world_frame: ''}\n", {"TagNodeConfig", "node.world_frame"});
  tag("tag_type.yaml", "node: {tf_timeout: soon}\n", {"node.tf_timeout", "wrong type"});
  tag("tag_nan.yaml", "node: {tf_timeout: .nan}\n", {"node.tf_timeout"});
  tag("tag_family.yaml", "tag_detector: {family: 99h9}\n", {"tag_detector"});

  auto grasp = [](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    const std::string path = writeTemp(name, text);
    expectError([&] { loadGraspNodeConfig(path); }, path, words);
  };
  grasp("grasp_tf.yaml", "node: {tf_timeout: -1}\n", {"GraspNodeConfig", "node.tf_timeout"});
  grasp("grasp_stale.yaml", "node: {stale_after: 11}\n", {"GraspNodeConfig", "node.stale_after"});
  grasp("grasp_budget.yaml", "node: {max_input_points: 10}\n", {"max_input_points"});
  grasp("grasp_budget_nan.yaml", "node: {max_input_points: .nan}\n", {"node.max_input_points"});
  grasp("grasp_object_points.yaml", "grasp_generator: {max_object_points: 10}\n", {"max_object_points"});
  grasp("grasp_queue.yaml", "node: {cloud_queue: 3}\n", {"unknown field 'node.cloud_queue'"});  // the newest cloud only
  grasp("grasp_rate.yaml", "node: {max_rate_hz: 0}\n", {"max_rate_hz"});
  grasp("grasp_gen.yaml", "grasp_generator: {top_k: 0}\n", {"grasp_generator"});
  grasp("grasp_cloud_target.yaml", "node: {cloud_target_topic: ''}\n", {"node.cloud_target_topic", "selector_topic"});

  auto obstacle = [](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    const std::string path = writeTemp(name, text);
    expectError([&] { loadObstacleNodeConfig(path); }, path, words);
  };
  obstacle("obst_rate.yaml", "node: {robot_config: realman_rm65_water2, publish_rate_hz: 0}\n",
           {"ObstacleNodeConfig", "node.publish_rate_hz"});
  obstacle("obst_tf.yaml", "node: {robot_config: realman_rm65_water2, tf_timeout: 6}\n",
           {"ObstacleNodeConfig", "node.tf_timeout"});
  obstacle("obst_state.yaml", "node: {robot_config: realman_rm65_water2, state_timeout: 0}\n",
           {"node.state_timeout"});
  obstacle("obst_stale.yaml", "node: {robot_config: realman_rm65_water2, stale_after: -1}\n",
           {"ObstacleNodeConfig", "node.stale_after"});
  obstacle("obst_budget.yaml", "node: {robot_config: realman_rm65_water2, max_input_points: 0}\n",
           {"node.max_input_points"});
  obstacle("obst_map.yaml", kObstacleNode + "obstacle_map: {resolution: -1}\n", {"obstacle_map"});
  obstacle("obst_no_node.yaml", "obstacle_map: {}\n", {"node"});
  obstacle("obst_no_robot.yaml", "node: {publish_rate_hz: 20}\n", {"node.robot_config"});
  obstacle("obst_bad_robot.yaml", "node: {robot_config: no_such_robot}\n", {"node.robot_config"});
}

TEST(NodeConfig, AnUnknownKeyFails) {
  const std::string tag = writeTemp("tag_unknown.yaml", "node: {tf_timout: 0.1}\n");
  expectError([&] { loadTagNodeConfig(tag); }, tag, {"unknown field 'node.tf_timout'", "node.tf_timeout"});
  const std::string tag_top = writeTemp("tag_unknown_top.yaml", "grasp_generator: {}\n");
  expectError([&] { loadTagNodeConfig(tag_top); }, tag_top, {"unknown field 'grasp_generator'"});
  const std::string grasp = writeTemp("grasp_unknown.yaml", "grasp_generator: {top_kk: 3}\n");
  expectError([&] { loadGraspNodeConfig(grasp); }, grasp, {"unknown field 'grasp_generator.top_kk'"});
  const std::string obstacle = writeTemp("obst_unknown.yaml", kObstacleNode + "obstacle_map: {resolutoin: 0.05}\n");
  expectError([&] { loadObstacleNodeConfig(obstacle); }, obstacle,
              {"unknown field 'obstacle_map.resolutoin'", "obstacle_map.resolution"});
}

// ---------------------------------------------------------------- shipped configs

TEST(NodeConfig, TheShippedConfigsLoad) {
  const std::string dir = test::configDir();
  const TagNodeConfig tag = loadTagNodeConfig(dir + "/perception/tag_node.yaml");
  EXPECT_EQ(tag.tf_timeout, 1.0);
  EXPECT_EQ(tag.target.tag_id, 0);
  for (const char* object : {"front", "middle", "back", "target"}) {
    SCOPED_TRACE(object);
    const TagNodeConfig t = loadTagNodeConfig(dir + "/demo/tag_" + object + ".yaml");
    EXPECT_EQ(t.world_frame, "odom");
  }
  const GraspNodeConfig grasp = loadGraspNodeConfig(dir + "/perception/grasp_node.yaml");
  EXPECT_EQ(grasp.target_topic, "/ehc/target_pose");
  EXPECT_EQ(grasp.targeting.target_gate, 0.15);
  for (const char* file : {"/perception/obstacle_node.yaml", "/demo/obstacle_node.yaml"}) {
    SCOPED_TRACE(file);
    const ObstacleNodeConfig o = loadObstacleNodeConfig(dir + file);
    EXPECT_TRUE(std::filesystem::equivalent(o.robot_config, test::robotYaml())) << o.robot_config;
    EXPECT_EQ(o.publish_rate_hz, 50.0);
  }
}

}  // namespace
}  // namespace ehc_perception
