// ConfigNode: unknown keys are errors (with the nearest known key), list elements and sections
// read by another program.
#include "ehc_common/config_node.h"
#include "ehc_test/errors.h"

#include <gtest/gtest.h>

#include <functional>

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
