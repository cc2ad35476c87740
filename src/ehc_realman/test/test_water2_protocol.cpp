// Water2 protocol: request formatting, reply parsing (well-formed and malformed), stream
// splitting with bounded memory, and the bridge configuration loader.

#include "ehc_realman/water2_base_bridge.h"
#include "ehc_realman/water2_protocol.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

using namespace ehc_realman;

TEST(Water2Protocol, FormatsRequests) {
  EXPECT_EQ(joyControlRequest(0.25, -0.5),
            "/api/joy_control?angular_velocity=-0.5000&linear_velocity=0.2500");
  EXPECT_EQ(joyControlRequest(-0.0, 0.0),
            "/api/joy_control?angular_velocity=0.0000&linear_velocity=0.0000");
  EXPECT_EQ(robotStatusRequest(), "/api/robot_status");
  EXPECT_THROW(joyControlRequest(NAN, 0.0), std::invalid_argument);
  EXPECT_THROW(joyControlRequest(0.0, INFINITY), std::invalid_argument);
}

TEST(Water2Protocol, ParsesStatusReplies) {
  const auto r = parseWater2Reply(
      R"({"type":"response","command":"/api/robot_status","uuid":"","status":"OK",)"
      R"("error_message":"","results":{"move_status":"idle","power_percent":87,)"
      R"("current_pose":{"x":1.5,"y":-2.25,"theta":0.75},"current_floor":1}})");
  EXPECT_EQ(r.type, "response");
  EXPECT_EQ(r.command, "/api/robot_status");
  EXPECT_TRUE(r.ok());
  ASSERT_TRUE(r.pose);
  EXPECT_DOUBLE_EQ(r.pose->x, 1.5);
  EXPECT_DOUBLE_EQ(r.pose->y, -2.25);
  EXPECT_DOUBLE_EQ(r.pose->theta, 0.75);
  const auto j = parseWater2Reply(
      "{\n  \"type\": \"response\",\n\t\"command\": \"/api/joy_control\", \"uuid\": \"\",\n"
      "  \"status\": \"OK\", \"error_message\": \"\"\n}");
  EXPECT_TRUE(j.ok());
  EXPECT_FALSE(j.pose);
  const auto e = parseWater2Reply(
      R"({"type":"response","command":"/api/joy_control","status":"ESTOP","error_message":"e-stop \"pressed\""})");
  EXPECT_FALSE(e.ok());
  EXPECT_EQ(e.error_message, "e-stop \"pressed\"");
}

TEST(Water2Protocol, MalformedRepliesThrowWithPrefix) {
  for (const std::string& bad :
       {std::string("not json at all"), std::string("[1, 2, 3]"), std::string("{\"command\":\"x\"}"),
        std::string(R"({"type":"response","command": ,,})"),
        std::string(R"({"type":"response","results":{"current_pose":{"x":"abc","y":1,"theta":0}}})"),
        std::string(R"({"type":"response","results":{"current_pose":{"x":1,"y":1}}})"),
        std::string(R"({"type":"response","results":{"current_pose":{"x":1e999,"y":1,"theta":0}}})"),
        std::string(R"({"type":"response","results":{"current_pose":[1,2,3]}})"),
        std::string(R"({"type":{"a":1}})"), std::string("")}) {
    try {
      parseWater2Reply(bad);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("[Water2Protocol]"), std::string::npos) << e.what();
    }
  }
}

TEST(JsonObjectSplitter, SplitsBackToBackObjectsAcrossChunks) {
  JsonObjectSplitter s;
  const std::string stream =
      R"({"type":"response","a":"}{ \" }"}{"type":"callback","n":{"x":1}}  )"
      "\n"
      R"({"type":"response"})";
  std::vector<std::string> out;
  for (char c : stream) {  // worst case: one byte at a time
    s.feed(&c, 1);
    std::string o;
    while (s.next(o)) out.push_back(o);
  }
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0], R"({"type":"response","a":"}{ \" }"})");
  EXPECT_EQ(out[1], R"({"type":"callback","n":{"x":1}})");
  EXPECT_EQ(parseWater2Reply(out[0]).type, "response");
  EXPECT_EQ(s.droppedBytes(), 0u);
}

TEST(JsonObjectSplitter, DropsGarbageAndOversizedObjectsWithBoundedMemory) {
  JsonObjectSplitter s(1024);
  s.feed("HTTP/1.1 500 oops\r\n");
  s.feed("{\"type\":\"big\",\"x\":\"" + std::string(5000, 'x') + "\"}");
  s.feed(R"({"type":"response"})");
  std::string o;
  ASSERT_TRUE(s.next(o));
  EXPECT_EQ(o, R"({"type":"response"})");
  EXPECT_FALSE(s.next(o));
  EXPECT_EQ(s.overflows(), 1u);
  EXPECT_GT(s.droppedBytes(), 5000u);
}

TEST(Water2BridgeConfig, LoadsTheShippedFileAndTightensWithTheRobot) {
  const auto c = loadWater2BridgeConfig(EHC_CONFIG_DIR "/realman/water2_base_bridge.yaml");
  EXPECT_EQ(c.host, "192.168.10.10");
  EXPECT_EQ(c.port, 31001);
  EXPECT_LE(c.max_linear_velocity, 0.5);
  EXPECT_LE(c.max_angular_velocity, 1.0);
  EXPECT_GE(c.resend_rate_hz, 10.0);
  EXPECT_LT(c.command_timeout, 0.2);
  EXPECT_NE(c.summary().find("31001"), std::string::npos);
}

TEST(Water2BridgeConfig, RejectsUnsafeValuesNamingTheField) {
  const std::string path = ::testing::TempDir() + "/bad_water2.yaml";
  auto expect_fail = [&](const std::string& body, const std::string& field) {
    {
      std::ofstream f(path);
      f << "water2_base_bridge:\n" << body;
    }
    try {
      loadWater2BridgeConfig(path);
      ADD_FAILURE() << "accepted " << body;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  expect_fail("  max_linear_velocity: 0.8\n", "max_linear_velocity");  // above the API bound
  expect_fail("  resend_rate_hz: 5\n", "resend_rate_hz");              // commands would lapse
  expect_fail("  port: 70000\n", "port");
  expect_fail("  command_timeout: slow\n", "command_timeout");
}

// The base's side (hardware stand-in, fake server): requests formatted by the bridge's client
// side come out of the splitter whole, back to back or cut anywhere, and the base's replies
// parse on the client side.
TEST(Water2Protocol, BaseSideSplitsAndParsesWhatTheClientSends) {
  const std::string stream = "garbage" + joyControlRequest(0.25, -0.5) + robotStatusRequest() +
                             joyControlRequest(-0.1, 0.0) + "\n" + "/api/unknown?x=1\n";
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    Water2RequestSplitter splitter;
    std::vector<std::string> out;
    std::string r;
    splitter.feed(stream.data(), cut);
    while (splitter.next(r)) out.push_back(r);
    splitter.feed(stream.data() + cut, stream.size() - cut);
    while (splitter.next(r)) out.push_back(r);
    ASSERT_EQ(out.size(), 4u) << "cut at " << cut;
    const Water2Request joy = parseWater2Request(out[0]);
    EXPECT_TRUE(joy.joy);
    EXPECT_EQ(joy.command, "/api/joy_control");
    EXPECT_DOUBLE_EQ(joy.linear, 0.25);
    EXPECT_DOUBLE_EQ(joy.angular, -0.5);
    EXPECT_EQ(parseWater2Request(out[1]).command, "/api/robot_status");
    EXPECT_FALSE(parseWater2Request(out[1]).joy);
    EXPECT_DOUBLE_EQ(parseWater2Request(out[2]).linear, -0.1);
    EXPECT_EQ(parseWater2Request(out[3]).command, "/api/unknown");
  }
  // A joy_control cut inside its last number waits for the rest.
  Water2RequestSplitter splitter;
  const std::string joy = joyControlRequest(0.25, -0.5);
  splitter.feed(joy.data(), joy.size() - 2);
  std::string r;
  EXPECT_FALSE(splitter.next(r));
  EXPECT_FALSE(parseWater2Request("/api/joy_control?angular_velocity=nan&linear_velocity=0.1").joy);
  EXPECT_FALSE(parseWater2Request("/api/joy_control?angular_velocity=0.1&linear_velocity=0.1x").joy);

  const Water2Reply status = parseWater2Reply(
      water2ResponseJson("/api/robot_status", "OK", "", Water2Pose{1.5, -2.0, 0.25}));
  EXPECT_TRUE(status.ok());
  EXPECT_EQ(status.command, "/api/robot_status");
  ASSERT_TRUE(status.pose.has_value());
  EXPECT_DOUBLE_EQ(status.pose->x, 1.5);
  EXPECT_DOUBLE_EQ(status.pose->y, -2.0);
  EXPECT_DOUBLE_EQ(status.pose->theta, 0.25);
  const Water2Reply error = parseWater2Reply(water2ResponseJson("/api/joy_control", "ESTOP", "say \"stop\""));
  EXPECT_FALSE(error.ok());
  EXPECT_EQ(error.error_message, "say \"stop\"");
  EXPECT_FALSE(error.pose.has_value());
}
