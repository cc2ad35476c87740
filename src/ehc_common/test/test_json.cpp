// jsonNumber: the project's one JSON number format (6 significant digits, non-finite -> null).
#include "ehc_common/json.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>

using ehc_common::Json;
using ehc_common::jsonLine;
using ehc_common::jsonNumber;

TEST(JsonNumber, RoundsToSixSignificantDigits) {
  EXPECT_EQ(jsonLine(jsonNumber(0.123456789)), "0.123457");
  EXPECT_EQ(jsonLine(jsonNumber(12345678.0)), "12345700.0");
  EXPECT_EQ(jsonLine(jsonNumber(-2.5)), "-2.5");
  EXPECT_EQ(jsonLine(jsonNumber(0.0)), "0.0");
}

TEST(JsonNumber, NonFiniteIsNull) {
  EXPECT_TRUE(jsonNumber(std::numeric_limits<double>::quiet_NaN()).is_null());
  EXPECT_TRUE(jsonNumber(std::numeric_limits<double>::infinity()).is_null());
  EXPECT_TRUE(jsonNumber(-std::numeric_limits<double>::infinity()).is_null());
}

TEST(JsonNumber, ParsesBackToThePrintedSixDigitValue) {
  const unsigned seed = ehc_test::testSeed("JsonNumber");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  std::uniform_int_distribution<int> exponent(-8, 8);
  for (int i = 0; i < 2000; ++i) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    const double back = Json::parse(jsonLine(jsonNumber(v))).get<double>();
    ASSERT_EQ(back, std::strtod(text, nullptr)) << "seed " << seed << " value " << v;
  }
}

TEST(Json, KeepsInsertionOrderOnOneLine) {
  Json j;
  j["z"] = 1;
  j["a"] = "x";
  j["m"] = jsonNumber(0.5);
  EXPECT_EQ(jsonLine(j), "{\"z\":1,\"a\":\"x\",\"m\":0.5}");
}

TEST(Json, InvalidUtf8IsReplacedNotThrown) {
  Json j;
  j["name"] = std::string("mug\xff\xfe");
  const std::string line = jsonLine(j);
  EXPECT_EQ(Json::parse(line)["name"].get<std::string>().substr(0, 3), "mug") << line;
}
