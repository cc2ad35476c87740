// The perception CLIs as a user runs them: ehc_detect_tags and ehc_grasps (exit codes,
// JSON output parsed back with yaml-cpp, clear errors).
#include "ehc_perception/grasp_generator.h"
#include "ehc_perception/tag_image_renderer.h"
#include "ehc_test/perception_fixtures.h"

#include <gtest/gtest.h>
#include <visp3/io/vpImageIo.h>
#include <yaml-cpp/yaml.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <sys/wait.h>

using namespace ehc_perception;
using namespace ehc_perception::test;

namespace {

struct CliRun {
  int code = -1;
  std::string out;  ///< stdout + stderr
};

CliRun run(const std::string& cmd) {
  CliRun r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf{};
  while (fgets(buf.data(), buf.size(), p)) r.out += buf.data();
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

}  // namespace

TEST(DetectTagsCli, PrintsTagPosesAsJson) {
  const ehc_control::PinholeCamera cam = ehc_control::loadPinholeCamera(cameraYaml());
  const Eigen::Isometry3d truth = facingTag(0.04, -0.02, 0.55, 0.3, -0.2, 0.5);
  const std::string img = "/tmp/ehc_cli_tag.png";
  vpImageIo::write(TagImageRenderer(cam).render({{7, 0.05, truth}}), img);
  const CliRun r = run(std::string(EHC_DETECT_TAGS_BIN) + " --image " + img + " --camera " +
                    cameraYaml() + " --tag-size 0.05 --family 36h11");
  ASSERT_EQ(r.code, 0) << r.out;
  const YAML::Node j = YAML::Load(r.out);
  ASSERT_TRUE(j.IsSequence());
  ASSERT_EQ(j.size(), 1u);
  EXPECT_EQ(j[0]["id"].as<int>(), 7);
  ASSERT_EQ(j[0]["T_cam_tag"].size(), 4u);
  ASSERT_EQ(j[0]["corners"].size(), 4u);
  const Eigen::Vector3d t(j[0]["T_cam_tag"][0][3].as<double>(), j[0]["T_cam_tag"][1][3].as<double>(),
                          j[0]["T_cam_tag"][2][3].as<double>());
  EXPECT_LT((t - truth.translation()).norm(), 0.006) << r.out;
  EXPECT_DOUBLE_EQ(j[0]["T_cam_tag"][3][3].as<double>(), 1.0);

  // No tag: an empty list.
  vpImageIo::write(vpImage<unsigned char>(480, 640, 100), "/tmp/ehc_cli_blank.png");
  const CliRun blank = run(std::string(EHC_DETECT_TAGS_BIN) + " --image /tmp/ehc_cli_blank.png --camera " +
                        cameraYaml() + " --tag-size 0.05");
  EXPECT_EQ(blank.code, 0);
  EXPECT_EQ(blank.out, "[]\n");
}

TEST(DetectTagsCli, BadInputsExitWithCode2AndAClearError) {
  const std::string bin = EHC_DETECT_TAGS_BIN;
  CliRun r = run(bin + " --image /nonexistent.png --camera " + cameraYaml() + " --tag-size 0.05");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("cannot read image '/nonexistent.png'"), std::string::npos) << r.out;

  std::ofstream("/tmp/ehc_cli_bad_camera.yaml") << "image_width: 640\n";
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera /tmp/ehc_cli_bad_camera.yaml --tag-size 0.05");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("[PinholeCamera]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("image_height"), std::string::npos) << r.out;

  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera " + cameraYaml() + " --tag-size -1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("default_tag_size"), std::string::npos) << r.out;
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera " + cameraYaml());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--tag-size"), std::string::npos) << r.out;
  // Image sizes read from the file are checked before the decoder allocates them
  // (a PNG header claiming 100000 x 100000 pixels, a PGM claiming 90000 x 90000).
  {
    const unsigned char png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                 0, 1, 0x86, 0xa0, 0, 1, 0x86, 0xa0, 8, 0, 0, 0, 0, 0, 0, 0, 0};
    std::ofstream("/tmp/ehc_cli_huge.png", std::ios::binary)
        .write(reinterpret_cast<const char*>(png), sizeof(png));
    std::ofstream("/tmp/ehc_cli_huge.pgm") << "P5\n# comment\n90000 90000\n255\n";
  }
  for (const char* huge : {"/tmp/ehc_cli_huge.png", "/tmp/ehc_cli_huge.pgm"}) {
    r = run(bin + " --image " + huge + " --camera " + cameraYaml() + " --tag-size 0.05");
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_NE(r.out.find("pixels (more than"), std::string::npos) << r.out;
  }
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera " + cameraYaml() + " --tag-size 5cm");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--tag-size: '5cm' is not a number"), std::string::npos) << r.out;
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera " + cameraYaml() + " --tag-size 0.05 --tagsize 1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--tagsize: unknown flag"), std::string::npos) << r.out;
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera " + cameraYaml() + " --tag-size 0.05 --family 99x1");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("unknown tag family"), std::string::npos) << r.out;
  // A camera that does not match the image size.
  std::ofstream("/tmp/ehc_cli_small_camera.yaml")
      << "image_width: 320\nimage_height: 240\ncamera_matrix: {data: [300, 0, 160, 0, 300, 120, 0, 0, 1]}\n";
  r = run(bin + " --image /tmp/ehc_cli_tag.png --camera /tmp/ehc_cli_small_camera.yaml --tag-size 0.05");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("image is 640x480"), std::string::npos) << r.out;
}

TEST(GraspsCli, WritesGraspsSortedByScore) {
  Surface s = cylinderSurface(0.03, 0.0, 0.12, 0.003, false, true);
  s.transform(pose(0.5, 0.0, 0.0, 0.0));
  savePcd("/tmp/ehc_cli_cyl.pcd", s.noisy(0.001, 1));
  const std::string out = "/tmp/ehc_cli_grasps.json";
  std::remove(out.c_str());
  const CliRun r = run(std::string(EHC_GRASPS_BIN) + " --cloud /tmp/ehc_cli_cyl.pcd --viewpoint 0,0,0.9 "
                    "--top 5 --out " + out);
  ASSERT_EQ(r.code, 0) << r.out;
  const YAML::Node j = YAML::Load(slurp(out));
  ASSERT_TRUE(j.IsSequence());
  ASSERT_GE(j.size(), 1u);
  ASSERT_LE(j.size(), 5u);
  for (std::size_t i = 0; i < j.size(); ++i) {
    ASSERT_EQ(j[i]["position"].size(), 3u);
    ASSERT_EQ(j[i]["orientation"].size(), 4u);
    Eigen::Quaterniond q(j[i]["orientation"][3].as<double>(), j[i]["orientation"][0].as<double>(),
                         j[i]["orientation"][1].as<double>(), j[i]["orientation"][2].as<double>());
    EXPECT_NEAR(q.norm(), 1.0, 1e-6);
    EXPECT_LT(j[i]["width"].as<double>(), 0.07);
    if (i > 0) {
      EXPECT_GE(j[i - 1]["score"].as<double>(), j[i]["score"].as<double>());
    }
  }
  const Eigen::Vector3d p(j[0]["position"][0].as<double>(), j[0]["position"][1].as<double>(),
                          j[0]["position"][2].as<double>());
  EXPECT_LT((p - Eigen::Vector3d(0.5, 0.0, 0.06)).head<2>().norm(), 0.01);
}

TEST(GraspsCli, NoGraspAndBadInputs) {
  const std::string bin = EHC_GRASPS_BIN;
  savePcd("/tmp/ehc_cli_empty.pcd", {});
  CliRun r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd --out /tmp/ehc_cli_empty.json");
  EXPECT_EQ(r.code, 3) << r.out;
  EXPECT_NE(r.out.find("no grasp: empty cloud"), std::string::npos) << r.out;
  EXPECT_EQ(slurp("/tmp/ehc_cli_empty.json"), "[]\n");

  r = run(bin + " --cloud /nonexistent.pcd --out /tmp/x.json");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("[PointCloudIO] cannot read '/nonexistent.pcd'"), std::string::npos) << r.out;
  r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--out: is required"), std::string::npos) << r.out;
  r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd --out /tmp/x.json --viewpoint 1,2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("--viewpoint: expects x,y,z"), std::string::npos) << r.out;
  r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd --out /tmp/x.json --top 0");
  EXPECT_EQ(r.code, 2);
  // Unparsable values name the flag.
  for (const std::string& bad : {std::string("--top 5.5"), std::string("--top 1e3"),
                                 std::string("--viewpoint 0,0,x"), std::string("--up 0,0,1,"),
                                 std::string("--mode objects"), std::string("--topp 3")}) {
    r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd --out /tmp/x.json " + bad);
    EXPECT_EQ(r.code, 2) << bad;
    EXPECT_NE(r.out.find(bad.substr(0, bad.find(' ')) + ":"), std::string::npos) << bad << ": " << r.out;
  }
  // A header claiming far more points than the file holds is refused before PCL allocates.
  std::ofstream("/tmp/ehc_cli_huge.pcd")
      << "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000000000\n"
         "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1000000000\nDATA binary\n0123456789ab";
  r = run(bin + " --cloud /tmp/ehc_cli_huge.pcd --out /tmp/x.json");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("header claims 1000000000 points"), std::string::npos) << r.out;
  std::ofstream("/tmp/ehc_cli_bad_grasps.yaml") << "grasp_generator: {voxel_size: 7}\n";
  r = run(bin + " --cloud /tmp/ehc_cli_empty.pcd --out /tmp/x.json --config /tmp/ehc_cli_bad_grasps.yaml");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.out.find("voxel_size"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("/tmp/ehc_cli_bad_grasps.yaml"), std::string::npos) << r.out;
}
