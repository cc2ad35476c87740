// ConfigNode: unknown keys are errors (with the nearest known key), list elements and sections
// read by another program.
#include "ehc_common/config_node.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>

#include <sys/stat.h>

using ehc_common::ConfigNode;

namespace {

using ehc_test::errorOf;

}  // namespace

TEST(ConfigNode, EveryKeyReadMeansNoUnknownKeys) {
  const auto root = ConfigNode::loadString("a: 1\nsec: {b: 2.5, c: [1, 2]}\n", "f.yaml", "Owner");
  EXPECT_EQ(root.get<int>("a", 0), 1);
  const auto sec = root.child("sec");
  EXPECT_DOUBLE_EQ(sec.get<double>("b", 0.0), 2.5);
  EXPECT_EQ(sec.getVector("c", Eigen::VectorXd()).size(), 2);
  EXPECT_TRUE(root.unknownKeys().empty());
  EXPECT_NO_THROW(root.rejectUnknownKeys());
}

TEST(ConfigNode, MisspelledKeyIsAnErrorNamingFileFieldAndTheNearestKey) {
  const auto root = ConfigNode::loadString("limits: {speed_scal: 0.2, max_linear_velocity: 0.2}\n",
                                           "realman.yaml", "RmArmAdapter");
  const auto limits = root.childOrEmpty("limits");
  EXPECT_DOUBLE_EQ(limits.get<double>("speed_scale", 1.0), 1.0);  // the misspelled key is not it
  EXPECT_DOUBLE_EQ(limits.get<double>("max_linear_velocity", 0.5), 0.2);
  ASSERT_EQ(root.unknownKeys(), std::vector<std::string>{"limits.speed_scal"});
  const std::string e = errorOf([&] { root.rejectUnknownKeys(); });
  EXPECT_NE(e.find("[RmArmAdapter]"), std::string::npos) << e;
  EXPECT_NE(e.find("realman.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("unknown field 'limits.speed_scal'"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'limits.speed_scale'"), std::string::npos) << e;
}

TEST(ConfigNode, UnreadSectionIsUnknownUnlessIgnored) {
  const auto root = ConfigNode::loadString("mine: {x: 1}\nnode: {rate: 5}\ntypo_section: {y: 2}\n", "f.yaml", "O");
  root.child("mine").get<int>("x", 0);
  root.ignore("node");
  EXPECT_EQ(root.unknownKeys(), std::vector<std::string>{"typo_section"});
  const std::string e = errorOf([&] { root.rejectUnknownKeys(); });
  EXPECT_NE(e.find("no parameter of that name"), std::string::npos) << e;
}

TEST(ConfigNode, AllUnknownKeysAreListed) {
  const auto root = ConfigNode::loadString("a: 1\nb: 2\nc: 3\n", "f.yaml", "O");
  root.get<int>("a", 0);
  const std::string e = errorOf([&] { root.rejectUnknownKeys(); });
  EXPECT_NE(e.find("'b'"), std::string::npos) << e;
  EXPECT_NE(e.find("'c'"), std::string::npos) << e;
}

TEST(ConfigNode, ListElementsAreCheckedKeyByKey) {
  const auto root = ConfigNode::loadString("objects:\n  - {name: a, approach: forward}\n  - {name: b, aproach: downward}\n",
                                           "seq.yaml", "Seq");
  ASSERT_EQ(root.listSize("objects"), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    const auto o = root.element("objects", i);
    o.require<std::string>("name");
    o.get<std::string>("approach", "forward");
  }
  EXPECT_EQ(root.unknownKeys(), std::vector<std::string>{"objects[1].aproach"});
  const std::string e = errorOf([&] { root.rejectUnknownKeys(); });
  EXPECT_NE(e.find("did you mean 'objects[1].approach'"), std::string::npos) << e;
}

TEST(ConfigNode, ElementOfANonListOrANonMappingFails) {
  const auto root = ConfigNode::loadString("objects: 3\nlist: [1, 2]\n", "f.yaml", "O");
  EXPECT_NE(errorOf([&] { root.listSize("objects"); }).find("field 'objects' must be a list"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.element("list", 0); }).find("field 'list[0]' must be a mapping"), std::string::npos);
  EXPECT_NE(errorOf([&] { root.element("list", 5); }).find("has no element 5"), std::string::npos);
  EXPECT_EQ(root.listSize("absent"), 0u);
}

TEST(ConfigNode, ChildrenShareTheRecordWithCopiesOfTheRoot) {
  const auto root = ConfigNode::loadString("s: {t: {u: 1}}\n", "f.yaml", "O");
  const ConfigNode copy = root;  // a loader that takes the root by value
  copy.child("s").child("t").get<int>("u", 0);
  EXPECT_TRUE(root.unknownKeys().empty());
}

TEST(ConfigNode, ValidateAppendsFileAndField) {
  struct P {
    double x = -1.0;
    void validate() const {
      if (x < 0.0) throw std::invalid_argument("[P] x must be >= 0");
    }
  };
  const auto root = ConfigNode::loadString("sec: {x: -1}\n", "f.yaml", "O");
  const std::string e = errorOf([&] { root.child("sec").validate(P{}); });
  EXPECT_NE(e.find("[P] x must be >= 0 (in f.yaml, sec)"), std::string::npos) << e;
}

namespace {
std::string writeFile(const std::string& path, const std::string& text) {
  const auto slash = path.find_last_of('/');
  ::mkdir(path.substr(0, slash).c_str(), 0755);
  std::ofstream(path) << text;
  return path;
}
}  // namespace

TEST(ConfigNode, ExtendsResolvesEachRelativePathAgainstTheFileThatSetIt) {
  // The base's relative path stays the base's, the extending file's own relative path is its own,
  // whichever folder each lives in.
  const std::string root = "/tmp/ehc_config_node_paths";
  ::mkdir(root.c_str(), 0755);
  writeFile(root + "/base/base.yaml", "robot: ../robots/r/robot.yaml\nsec: {camera: cam.yaml, other: 1}\nlist: [{p: a.yaml}]\n");
  writeFile(root + "/user/over.yaml", "extends: ../base/base.yaml\nsec: {other: 2, mine: data.bin}\n");
  const auto n = ConfigNode::loadFile(root + "/user/over.yaml", "Test");
  const std::string base = root + "/user/../base";  // as the extends chain names it
  EXPECT_EQ(n.requirePath("robot"), base + "/../robots/r/robot.yaml");
  EXPECT_EQ(n.child("sec").requirePath("camera"), base + "/cam.yaml");
  EXPECT_EQ(n.child("sec").requirePath("mine"), root + "/user/data.bin");
  EXPECT_EQ(n.element("list", 0).requirePath("p"), base + "/a.yaml");
  EXPECT_EQ(n.getPath("absent", "x"), "x");
  EXPECT_EQ(n.fileOf("robot"), base + "/base.yaml");
  EXPECT_EQ(n.fileOf("sec.other"), root + "/user/over.yaml");
  // A list replaced by the extending file is the extending file's.
  writeFile(root + "/user/over2.yaml", "extends: ../base/base.yaml\nlist: [{p: b.yaml}]\n");
  const auto m = ConfigNode::loadFile(root + "/user/over2.yaml", "Test");
  EXPECT_EQ(m.element("list", 0).requirePath("p"), root + "/user/b.yaml");
  // Three files: each value resolves against its own file.
  writeFile(root + "/third/top.yaml", "extends: ../user/over.yaml\nrobot: /abs/robot.yaml\n");
  const auto t = ConfigNode::loadFile(root + "/third/top.yaml", "Test");
  EXPECT_EQ(t.requirePath("robot"), "/abs/robot.yaml");
  EXPECT_EQ(t.child("sec").requirePath("mine"), root + "/third/../user/data.bin");
  EXPECT_EQ(t.child("sec").requirePath("camera"), root + "/third/../user/../base/cam.yaml");
  writeFile(root + "/user/empty.yaml", "extends: ../base/base.yaml\nrobot: ''\n");
  const std::string e = errorOf([&] { ConfigNode::loadFile(root + "/user/empty.yaml", "Test").requirePath("robot"); });
  EXPECT_NE(e.find("empty.yaml: field 'robot' must not be empty"), std::string::npos) << e;
}

TEST(ConfigNode, ErrorsNameTheFileTheBadValueCameFrom) {
  const std::string root = "/tmp/ehc_config_node_origin";
  ::mkdir(root.c_str(), 0755);
  writeFile(root + "/base.yaml", "a: {x: abc, y: 1}\n");
  writeFile(root + "/over.yaml", "extends: base.yaml\na: {y: def}\nb: 2\n");
  const auto n = ConfigNode::loadFile(root + "/over.yaml", "Test");
  const std::string from_base = errorOf([&] { n.child("a").require<double>("x"); });
  EXPECT_NE(from_base.find(root + "/base.yaml (through 'extends' of " + root + "/over.yaml): field 'a.x'"),
            std::string::npos) << from_base;
  const std::string from_over = errorOf([&] { n.child("a").require<double>("y"); });
  EXPECT_NE(from_over.find("[Test] " + root + "/over.yaml: field 'a.y'"), std::string::npos) << from_over;
  n.ignore("a");
  const std::string unknown = errorOf([&] { n.rejectUnknownKeys(); });
  EXPECT_NE(unknown.find(root + "/over.yaml: unknown field 'b'"), std::string::npos) << unknown;
}

TEST(ConfigNode, GetInRangeNamesFileAndField) {
  const auto root = ConfigNode::loadString("node: {rate: 5000, ok: 50}\n", "f.yaml", "O");
  EXPECT_EQ(root.child("node").getInRange("ok", 1.0, 1.0, 1000.0), 50.0);
  EXPECT_EQ(root.child("node").getInRange("absent", 7, 1.0, 1000.0), 7);
  const std::string e = errorOf([&] { root.child("node").getInRange("rate", 1.0, 1.0, 1000.0); });
  EXPECT_NE(e.find("[O] f.yaml: field 'node.rate' = 5000 is outside [1, 1000]"), std::string::npos) << e;
}
