#include <regolith/core/Message.hpp>

#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <random>
#include <string>

using regolith::core::format;
using regolith::core::Message;
using regolith::core::number;

TEST(Message, NumbersAreTheShortestTextThatReadsBackExactly) {
  EXPECT_EQ(number(1e-9), "1e-09");  // std::to_string would print 0.000000
  EXPECT_EQ(number(0.1), "0.1");
  EXPECT_EQ(number(3396190.0), "3396190");
  EXPECT_EQ(number(-0.5), "-0.5");
  EXPECT_EQ(number(0.1F), "0.1");
  EXPECT_EQ(number(std::numeric_limits<double>::quiet_NaN()), "nan");
  EXPECT_EQ(number(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(number(-std::numeric_limits<float>::infinity()), "-inf");
  EXPECT_EQ(number(std::size_t{18446744073709551615ULL}), "18446744073709551615");
  EXPECT_EQ(number(-3), "-3");

  // Round trip through the standard parser, over doubles of every magnitude.
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<int> exponent(-320, 300);
  std::uniform_real_distribution<double> mantissa(-10.0, 10.0);
  for (int i = 0; i < 20000; ++i) {
    const double v = mantissa(rng) * std::pow(10.0, exponent(rng));
    const std::string s = number(v);
    double back = 0.0;
    const auto r = std::from_chars(s.data(), s.data() + s.size(), back);
    ASSERT_EQ(r.ec, std::errc()) << s;
    ASSERT_EQ(back, v) << s;
  }
}

TEST(Message, PartsAreJoinedInTheHouseFormat) {
  EXPECT_EQ(format({.operation = "store::open()",
                    .file = "/data/x.h5",
                    .field = "grid 'victoria' spacing",
                    .value = "-1 m",
                    .expected = "> 0"}),
            "store::open(): /data/x.h5: grid 'victoria' spacing is -1 m, expected > 0");
  EXPECT_EQ(format({.operation = "TopoGrid()",
                    .field = "spacing",
                    .value = number(1e-9) + " m",
                    .expected = "finite and > 0"}),
            "TopoGrid(): spacing is 1e-09 m, expected finite and > 0");
  EXPECT_EQ(format({.operation = "store::open()",
                    .file = "/data/x.h5",
                    .field = "attribute 'kind'",
                    .expected = "'dem' or 'planet'"}),
            "store::open(): /data/x.h5: attribute 'kind', expected 'dem' or 'planet'");
  EXPECT_EQ(format({.operation = "Pager::heights()", .field = "cache budget", .value = "0"}),
            "Pager::heights(): cache budget is 0");
}
