// fixedDecimals and csvField: the one "number with N decimals" and the one CSV field of the text
// EHC-MM writes.
#include "ehc_common/text_format.h"
#include "ehc_test/test_seed.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <string>

using ehc_common::fixedDecimals;

TEST(FixedDecimals, RoundsToTheGivenDecimals) {
  EXPECT_EQ(fixedDecimals(0.12345, 3), "0.123");
  EXPECT_EQ(fixedDecimals(2.5, 0), "2");  // round half to even, as printf
  EXPECT_EQ(fixedDecimals(-12.25, 1), "-12.2");
  EXPECT_EQ(fixedDecimals(7.0, 2), "7.00");
}

TEST(FixedDecimals, ZeroHasNoSign) {
  EXPECT_EQ(fixedDecimals(-0.0, 3), "0.000");
  EXPECT_EQ(fixedDecimals(-0.0004, 3), "0.000");
  EXPECT_EQ(fixedDecimals(-0.4, 0), "0");
  EXPECT_EQ(fixedDecimals(-0.0006, 3), "-0.001");
}

TEST(FixedDecimals, NonFiniteIsNamed) {
  EXPECT_EQ(fixedDecimals(std::numeric_limits<double>::quiet_NaN(), 2), "nan");
  EXPECT_EQ(fixedDecimals(std::numeric_limits<double>::infinity(), 2), "inf");
  EXPECT_EQ(fixedDecimals(-std::numeric_limits<double>::infinity(), 2), "-inf");
}

TEST(FixedDecimals, ReadsBackWithinHalfALastDigitOnRandomValues) {
  const unsigned seed = ehc_test::testSeed("FixedDecimals");
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> exponent(-6.0, 300.0);
  std::uniform_int_distribution<int> decimals(0, 6), sign(0, 1);
  for (int i = 0; i < 2000; ++i) {
    const double v = (sign(rng) ? -1.0 : 1.0) * std::pow(10.0, exponent(rng));
    const int d = decimals(rng);
    const std::string s = fixedDecimals(v, d);
    ASSERT_EQ(s.find('.') == std::string::npos ? 0 : static_cast<int>(s.size() - s.find('.') - 1), d) << s;
    const double back = std::strtod(s.c_str(), nullptr);
    ASSERT_LE(std::abs(back - v), 0.5 * std::pow(10.0, -d) + 1e-15 * std::abs(v)) << v << " -> " << s;
  }
}

TEST(CsvField, QuotesTheFieldAndDoublesInnerQuotes) {
  EXPECT_EQ(ehc_common::csvField(""), "\"\"");
  EXPECT_EQ(ehc_common::csvField("a, b"), "\"a, b\"");
  EXPECT_EQ(ehc_common::csvField("say \"hi\""), "\"say \"\"hi\"\"\"");
  EXPECT_EQ(ehc_common::csvField("two\nlines"), "\"two\nlines\"");
}
