// StepScheduler: the stepping policy both fake robots (ehc_sim_node, ehc_kinematic_sim_node)
// share. Lock-step: a step only when the state is answered (never on a timeout, however much
// wall time passes); an unanswered state is resent; NaN / wrongly sized commands are answers
// that are counted and executed as zero. Free-run: one step per dt of wall time, stale
// commands zeroed, no catching up. Wall times are plain numbers here: nothing is timed.

#include "ehc_common/node_params.h"
#include "ehc_sim/step_scheduler.h"

#include <gtest/gtest.h>

#include <limits>

using ehc_sim::AckNode;
using ehc_sim::AckStream;
using ehc_sim::StepAction;
using ehc_sim::StepScheduler;

namespace {

ehc_control::RobotConfig robot() {
  return ehc_control::loadRobotConfig(std::string(EHC_CONFIG_DIR) + "/robots/realman_rm65_water2/robot.yaml");
}

ehc_sim::FakeRobotConfig config(bool free_run) {
  ehc_sim::FakeRobotConfig c;
  c.robot_file = "robot.yaml";  // not read by the scheduler
  c.dt = 0.01;
  c.free_run = free_run;
  c.state_republish_period = 1.0;
  c.command_timeout = 0.5;
  return c;
}

const std::vector<std::string> kNames = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
const std::vector<double> kRates = {0.1, -0.2, 0.3, -0.4, 0.5, -0.6};
const double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::int64_t kT0 = 1'000'000'000;  // state stamps, ns
constexpr std::int64_t kT1 = 1'010'000'000;

}  // namespace

TEST(StepScheduler, LockStepNeverAdvancesWithoutAnAnswer) {
  StepScheduler s(robot(), config(false));
  ASSERT_TRUE(s.lockStep());
  s.statePublished(100.0, kT0, true);
  EXPECT_EQ(s.next(100.5), StepAction::Wait);
  // However long nobody answers: the state is resent, time never steps.
  double last_publish = 100.0;
  for (double wall = 100.0; wall < 1100.0; wall += 0.25) {
    const StepAction a = s.next(wall);
    ASSERT_NE(a, StepAction::Step) << "stepped without an answer at wall " << wall;
    if (a == StepAction::RepublishState) {
      EXPECT_GT(wall - last_publish, 1.0);
      s.statePublished(wall, kT0, false);
      last_publish = wall;
    }
  }
  EXPECT_GT(last_publish, 1098.0) << "resent every state_republish_period";
  // Half an answer (the twist): no step; the state is still resent (the other half may have
  // been lost while the controller's publisher was connecting: waiting for it would stop time
  // for good).
  EXPECT_EQ(s.onBaseTwist(1100.0, 0.1, 0.0, 0.2), "");
  s.statePublished(1100.0, kT0, false);
  EXPECT_EQ(s.next(1100.5), StepAction::Wait);
  EXPECT_EQ(s.next(1200.0), StepAction::RepublishState);
  s.statePublished(1200.0, kT0, false);  // not fresh: the twist still counts
  EXPECT_EQ(s.next(1200.0), StepAction::Wait);
  // The arm command of another state is no answer either.
  EXPECT_NE(s.onArmCommand(1200.0, kT1, kNames, kRates), "");
  EXPECT_EQ(s.next(1200.0), StepAction::Wait);
  EXPECT_EQ(s.counters().arm_stale, 1);
  // The full answer: step with it.
  EXPECT_EQ(s.onArmCommand(1200.0, kT0, kNames, kRates), "");
  EXPECT_EQ(s.next(1200.0), StepAction::Step);
  const Eigen::VectorXd c = s.command();
  ASSERT_EQ(c.size(), 8);
  EXPECT_DOUBLE_EQ(c[0], 0.1);
  EXPECT_DOUBLE_EQ(c[1], 0.2);
  for (int i = 0; i < 6; ++i) EXPECT_DOUBLE_EQ(c[2 + i], kRates[static_cast<std::size_t>(i)]);
  // The next state needs its own answer.
  s.statePublished(1200.0, kT1, true);
  EXPECT_EQ(s.next(1200.0), StepAction::Wait);
}

TEST(StepScheduler, AckGateHoldsAStepUntilEveryNodeIsDoneWithTheImage) {
  // Perception in the lock-step. Two tag nodes; an image with the state at kT0.
  StepScheduler s(robot(), config(false));
  s.setAckGate({AckNode::parse("ehc_tag_a"), AckNode::parse("ehc_tag_b:image")}, 0);
  auto answer = [&](double wall, std::int64_t t) {
    EXPECT_EQ(s.onBaseTwist(wall, 0.0, 0.0, 0.0), "");
    EXPECT_EQ(s.onArmCommand(wall, t, kNames, kRates), "");
  };
  // Nodes join with their first acknowledgement: before that they hold nothing back.
  s.statePublished(100.0, kT0 - 10'000'000, true);
  s.framePublished(AckStream::Image, kT0 - 10'000'000);
  answer(100.0, kT0 - 10'000'000);
  EXPECT_EQ(s.next(100.0), StepAction::Step);
  EXPECT_EQ(s.onAck("ehc_tag_a", kT0 - 10'000'000), "");
  EXPECT_EQ(s.onAck("ehc_tag_b", kT0 - 10'000'000), "");
  s.statePublished(100.0, kT0, true);
  s.framePublished(AckStream::Image, kT0);
  answer(100.0, kT0);
  // However long the detection takes (a loaded machine): no step, and no resending.
  for (double wall = 100.0; wall < 200.0; wall += 0.5) ASSERT_EQ(s.next(wall), StepAction::Wait);
  EXPECT_NE(s.ackWait().find("ehc_tag_a"), std::string::npos) << s.ackWait();
  EXPECT_NE(s.onAck("ehc_tag_c", kT0), "") << "not a gate node";
  EXPECT_EQ(s.onAck("/ehc_tag_a", kT0), "");  // ROS node names start with '/'
  EXPECT_EQ(s.next(200.0), StepAction::Wait);
  EXPECT_NE(s.ackWait().find("ehc_tag_b"), std::string::npos);
  EXPECT_EQ(s.onAck("ehc_tag_b", kT0), "");
  EXPECT_EQ(s.ackWait(), "");
  EXPECT_EQ(s.next(200.0), StepAction::Step);
  // The next state has no image: it steps on the controller's answer alone.
  s.statePublished(200.0, kT1, true);
  answer(200.0, kT1);
  EXPECT_EQ(s.next(200.0), StepAction::Step);

  // With a lag of 2 steps an image holds only the step that would pass it by more than that;
  // an acknowledgement of a later image covers an earlier one the node skipped.
  StepScheduler lag(robot(), config(false));
  lag.setAckGate({AckNode::parse("ehc_tag_a")}, 20'000'000);
  const std::int64_t dt = 10'000'000;
  EXPECT_EQ(lag.onAck("ehc_tag_a", 0), "");  // joined
  lag.statePublished(0.0, kT0, true);
  lag.framePublished(AckStream::Image, kT0);
  for (int k = 0; k < 3; ++k) {
    const std::int64_t t = kT0 + k * dt;
    if (k > 0) lag.statePublished(0.0, t, true);
    if (k == 1) lag.framePublished(AckStream::Image, t);
    EXPECT_EQ(lag.onBaseTwist(0.0, 0.0, 0.0, 0.0), "");
    EXPECT_EQ(lag.onArmCommand(0.0, t, kNames, kRates), "");
    if (k < 2) {
      EXPECT_EQ(lag.next(0.0), StepAction::Step) << "step " << k << ": within the lag";
    } else {
      EXPECT_EQ(lag.next(0.0), StepAction::Wait) << "step " << k << ": would pass the image at kT0 by > 2 steps";
      EXPECT_EQ(lag.onAck("ehc_tag_a", kT0 + dt), "");  // the later image: both done
      EXPECT_EQ(lag.next(0.0), StepAction::Step);
    }
  }
  EXPECT_THROW(lag.setAckGate({AckNode::parse("x")}, -1), std::invalid_argument);
}

TEST(StepScheduler, AckGateHoldsEachNodeOnlyToItsOwnStream) {
  // A cloud consumer (the grasp node) and a state consumer (the grasp sequencer) beside an image
  // consumer: each is held only to the frames of its stream.
  StepScheduler s(robot(), config(false));
  s.setAckGate({AckNode::parse("tag"), AckNode::parse("/grasp:cloud"), AckNode::parse("sequencer:state")}, 0);
  auto answer = [&](std::int64_t t) {
    EXPECT_EQ(s.onBaseTwist(0.0, 0.0, 0.0, 0.0), "");
    EXPECT_EQ(s.onArmCommand(0.0, t, kNames, kRates), "");
  };
  s.statePublished(0.0, kT0, true);  // nobody joined yet: nothing held
  s.framePublished(AckStream::Image, kT0);
  s.framePublished(AckStream::Cloud, kT0);
  answer(kT0);
  EXPECT_EQ(s.next(0.0), StepAction::Step);
  for (const char* n : {"tag", "grasp", "sequencer"}) EXPECT_EQ(s.onAck(n, kT0), "") << n;  // all joined
  // kT1: an image only (no cloud). The cloud consumer is not held by it; the image and the
  // state consumers are, each until it acknowledges.
  s.statePublished(0.0, kT1, true);
  s.framePublished(AckStream::Image, kT1);
  answer(kT1);
  EXPECT_EQ(s.next(0.0), StepAction::Wait);
  EXPECT_NE(s.ackWait().find("tag (image"), std::string::npos) << s.ackWait();
  EXPECT_EQ(s.onAck("tag", kT1), "");
  EXPECT_EQ(s.next(0.0), StepAction::Wait);
  EXPECT_NE(s.ackWait().find("sequencer (state"), std::string::npos) << s.ackWait();
  EXPECT_EQ(s.onAck("sequencer", kT1), "");
  EXPECT_EQ(s.ackWait(), "");
  EXPECT_EQ(s.next(0.0), StepAction::Step);
  // kT2: a cloud: the grasp node holds the step until it is done with it.
  const std::int64_t kT2 = kT1 + (kT1 - kT0);
  s.statePublished(0.0, kT2, true);
  s.framePublished(AckStream::Cloud, kT2);
  answer(kT2);
  EXPECT_EQ(s.onAck("sequencer", kT2), "");
  EXPECT_EQ(s.next(0.0), StepAction::Wait);
  EXPECT_NE(s.ackWait().find("grasp (cloud"), std::string::npos) << s.ackWait();
  EXPECT_EQ(s.onAck("grasp", kT2), "");
  EXPECT_EQ(s.next(0.0), StepAction::Step);
  // After a reset every node joins again.
  s.reset();
  s.statePublished(0.0, kT0, true);
  answer(kT0);
  EXPECT_EQ(s.next(0.0), StepAction::Step);

  // Specs: "name[:state|image|cloud]"; bad ones are clear errors.
  EXPECT_EQ(AckNode::parse("a").stream, AckStream::Image);
  EXPECT_EQ(AckNode::parse("a:state").stream, AckStream::State);
  EXPECT_EQ(AckNode::parse("/ns/a:cloud").name, "ns/a");
  EXPECT_THROW(AckNode::parse(":cloud"), std::invalid_argument);
  try {
    AckNode::parse("a:depth");
    FAIL() << "unknown stream accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown stream 'depth'"), std::string::npos) << e.what();
  }
  StepScheduler twice(robot(), config(false));
  EXPECT_THROW(twice.setAckGate({AckNode::parse("a"), AckNode::parse("a:cloud")}, 0), std::invalid_argument);
}

TEST(StepScheduler, AnAcknowledgementFromTheFutureIsIgnoredAndOpensNothing) {
  // One stray far-future stamp (a wrong clock, a stray publisher) used to count as done with
  // every frame up to it: the gate stayed open for the rest of the run. It is ignored, with the
  // reason; acknowledgements of frames that exist still count, up to one step ahead.
  StepScheduler s(robot(), config(false));
  s.setAckGate({AckNode::parse("tag"), AckNode::parse("seq:state")}, 0);
  const std::int64_t dt = kT1 - kT0;
  EXPECT_EQ(s.onAck("tag", 0), "");  // "ready": joined
  EXPECT_EQ(s.onAck("seq", 0), "");
  for (int k = 0; k < 50; ++k) {
    const std::int64_t t = kT0 + k * dt;
    s.statePublished(0.0, t, true);
    s.framePublished(AckStream::Image, t);
    EXPECT_EQ(s.onBaseTwist(0.0, 0.0, 0.0, 0.0), "");
    EXPECT_EQ(s.onArmCommand(0.0, t, kNames, kRates), "");
    const std::string why = s.onAck("tag", t + 1000 * dt);  // 10 s ahead
    EXPECT_NE(why.find("'tag' acknowledged"), std::string::npos) << why;
    EXPECT_NE(why.find("ahead of the newest frame"), std::string::npos) << why;
    EXPECT_NE(s.onAck("seq", std::numeric_limits<std::int64_t>::max()), "");
    // Still held: neither node is done with the frame of t.
    ASSERT_EQ(s.next(0.0), StepAction::Wait) << "step " << k;
    EXPECT_NE(s.ackWait().find("tag (image"), std::string::npos) << s.ackWait();
    EXPECT_EQ(s.onAck("tag", t), "");
    EXPECT_EQ(s.next(0.0), StepAction::Wait);
    EXPECT_EQ(s.onAck("seq", t), "");
    ASSERT_EQ(s.next(0.0), StepAction::Step) << "step " << k;
  }
  EXPECT_EQ(s.onAck("seq", kT0 + 50 * dt), "");  // one step ahead of the newest frame: within the bound
  // After a reset time restarts: an acknowledgement of a frame before it is from the future too.
  s.reset();
  s.statePublished(0.0, kT0, true);
  s.framePublished(AckStream::Image, kT0);
  EXPECT_NE(s.onAck("tag", kT0 + 40 * dt), "");
  EXPECT_EQ(s.onAck("tag", kT0), "");
}

TEST(StepScheduler, RejectedCommandsAreCountedAnswersExecutedAsZero) {
  StepScheduler s(robot(), config(false));
  s.statePublished(0.0, kT0, true);
  std::vector<double> nan_rates = kRates;
  nan_rates[3] = kNaN;
  EXPECT_NE(s.onArmCommand(0.0, kT0, kNames, nan_rates), "");
  EXPECT_EQ(s.onBaseTwist(0.0, 0.1, 0.0, 0.0), "");
  ASSERT_EQ(s.next(0.0), StepAction::Step) << "a rejected command does not stall lock-step";
  EXPECT_TRUE(s.command().tail(6).isZero());
  EXPECT_DOUBLE_EQ(s.command()[0], 0.1);
  EXPECT_EQ(s.counters().arm_rejected, 1);

  s.statePublished(0.0, kT1, true);
  EXPECT_NE(s.onArmCommand(0.0, kT1, kNames, std::vector<double>(5, 0.1)), "") << "wrong size";
  EXPECT_NE(s.onBaseTwist(0.0, kNaN, 0.0, 0.0), "");
  ASSERT_EQ(s.next(0.0), StepAction::Step);
  EXPECT_TRUE(s.command().isZero());
  EXPECT_EQ(s.counters().arm_rejected, 2);
  EXPECT_EQ(s.counters().base_rejected, 1);

  s.reset();
  EXPECT_EQ(s.counters().arm_rejected, 0);
  EXPECT_TRUE(s.command().isZero());
}

TEST(StepScheduler, PacingDelaysAnAnsweredStepButNeverMakesOne) {
  ehc_sim::FakeRobotConfig c = config(false);
  c.max_real_time_factor = 10.0;  // dt 10 ms -> at least 1 ms of wall time per step
  StepScheduler s(robot(), c);
  s.statePublished(5.0, kT0, true);
  EXPECT_EQ(s.onBaseTwist(5.0, 0.0, 0.0, 0.0), "");
  EXPECT_EQ(s.onArmCommand(5.0, kT0, kNames, kRates), "");
  EXPECT_EQ(s.next(5.0005), StepAction::Wait);
  EXPECT_EQ(s.next(5.0011), StepAction::Step);
  EXPECT_LE(s.callbackWait(), 0.00025 + 1e-12) << "wakes up in time for the next step";
  // Unanswered: paced or not, never a step.
  s.statePublished(5.0011, kT1, true);
  for (double wall = 5.0011; wall < 50.0; wall += 0.01) ASSERT_NE(s.next(wall), StepAction::Step);
}

TEST(StepScheduler, FreeRunStepsEveryPeriodAndZeroesStaleCommands) {
  StepScheduler s(robot(), config(true));
  ASSERT_FALSE(s.lockStep());
  s.statePublished(10.0, kT0, true);
  EXPECT_EQ(s.next(10.0), StepAction::Wait);  // first step one period later
  EXPECT_EQ(s.next(10.005), StepAction::Wait);
  // Any stamp is accepted in free-run.
  EXPECT_EQ(s.onArmCommand(10.005, 42, kNames, kRates), "");
  EXPECT_EQ(s.onBaseTwist(10.005, 0.2, 0.0, 0.0), "");
  ASSERT_EQ(s.next(10.0101), StepAction::Step);
  EXPECT_DOUBLE_EQ(s.command()[0], 0.2);
  EXPECT_EQ(s.next(10.0102), StepAction::Wait);
  ASSERT_EQ(s.next(10.0201), StepAction::Step);
  EXPECT_DOUBLE_EQ(s.command()[0], 0.2) << "commands 15 ms old are fresh";
  // After a stall of 1 s: zero commands (older than 0.5 s) and no catching up on the ~100
  // missed periods (the schedule restarts at the current time).
  ASSERT_EQ(s.next(11.03), StepAction::Step);
  EXPECT_TRUE(s.command().isZero());
  int steps = 0;
  for (double wall = 11.031; wall < 11.0395; wall += 0.001) steps += s.next(wall) == StepAction::Step;
  EXPECT_LE(steps, 1);
  EXPECT_EQ(s.next(11.0501), StepAction::Step);
}

TEST(StepScheduler, ActionNames) {
  EXPECT_STREQ(ehc_sim::toString(StepAction::Wait), "wait");
  EXPECT_STREQ(ehc_sim::toString(StepAction::Step), "step");
  EXPECT_STREQ(ehc_sim::toString(StepAction::RepublishState), "republish_state");
}

// The simulator node's _lockstep_acks / _lockstep_max_lag, parsed in the core: a YAML list or
// rosrun's one string; empty means no gate; a malformed entry or lag is a [StepScheduler] error
// naming it.
TEST(AckGateConfig, ParsesTheNodeParameters) {
  EXPECT_EQ(ehc_common::splitNameList("[ehc_tag_node, ehc_grasp_node:cloud,ehc_grasp_sequencer_node:state]"),
            (std::vector<std::string>{"ehc_tag_node", "ehc_grasp_node:cloud", "ehc_grasp_sequencer_node:state"}));
  EXPECT_EQ(ehc_common::splitNameList("a b"), (std::vector<std::string>{"a", "b"}));
  const ehc_sim::AckGateConfig gate =
      ehc_sim::parseAckGate(ehc_common::splitNameList("[tag, /grasp:cloud, sequencer:state]"), 0.02);
  ASSERT_EQ(gate.nodes.size(), 3u);
  EXPECT_EQ(gate.nodes[0].name, "tag");
  EXPECT_EQ(gate.nodes[0].stream, AckStream::Image);
  EXPECT_EQ(gate.nodes[1].name, "grasp");
  EXPECT_EQ(gate.nodes[1].stream, AckStream::Cloud);
  EXPECT_EQ(gate.nodes[2].stream, AckStream::State);
  EXPECT_EQ(gate.maxLagNs(), 20'000'000);
  EXPECT_EQ(gate.summary(), " tag (image) grasp (cloud) sequencer (state)");
  StepScheduler s(robot(), config(false));
  s.setAckGate(gate.nodes, gate.maxLagNs());
  EXPECT_EQ(s.notJoined(), "tag grasp sequencer");
}

TEST(AckGateConfig, EmptyMeansNoGate) {
  for (const std::string text : {"", "[]", " , [ ] "}) {
    EXPECT_TRUE(ehc_common::splitNameList(text).empty()) << text;
    EXPECT_TRUE(ehc_sim::parseAckGate(ehc_common::splitNameList(text), 0.0).nodes.empty()) << text;
  }
  EXPECT_EQ(ehc_sim::parseAckGate({}, 0.0).summary(), "");
}

TEST(AckGateConfig, MalformedEntriesAreClearErrors) {
  auto error = [](const std::vector<std::string>& specs, double lag) {
    try {
      ehc_sim::parseAckGate(specs, lag);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string stream = error(ehc_common::splitNameList("[tag, grasp:depth]"), 0.0);
  EXPECT_EQ(stream.rfind("[StepScheduler] ", 0), 0u) << stream;
  EXPECT_NE(stream.find("unknown stream 'depth' in 'grasp:depth'"), std::string::npos) << stream;
  const std::string name = error({"tag", ":cloud"}, 0.0);
  EXPECT_NE(name.find("[StepScheduler] acknowledgement gate: empty node name in ':cloud'"), std::string::npos) << name;
  EXPECT_NE(error({""}, 0.0).find("empty node name"), std::string::npos);  // an empty YAML list element
  for (const double lag : {-0.1, 11.0, std::numeric_limits<double>::quiet_NaN()}) {
    const std::string why = error({"tag"}, lag);
    EXPECT_EQ(why.rfind("[StepScheduler] acknowledgement gate: max lag ", 0), 0u) << why;
    EXPECT_NE(why.find("outside [0, 10] s"), std::string::npos) << why;
  }
}
