// spec/exact_time: decimal seconds to integer nanoseconds and back, exactly
// (issue 36). Hand-computed values, and a round trip over random nanoseconds.
#include "spec/exact_time.hpp"

#include <gtest/gtest.h>

#include <random>

using rvc::spec::parse_seconds;
using rvc::spec::SecondsStatus;
using rvc::spec::seconds_text;

namespace {
int64_t ns_of(const char* text) {
  int64_t ns = -12345;
  EXPECT_EQ(parse_seconds(text, ns), SecondsStatus::Ok) << text;
  return ns;
}
}  // namespace

TEST(ExactTime, DecimalSecondsAreReadExactly) {
  EXPECT_EQ(ns_of("1746721937.599626818"), 1746721937599626818);
  EXPECT_EQ(ns_of("0.025"), 25000000);
  EXPECT_EQ(ns_of("25e-3"), 25000000);
  EXPECT_EQ(ns_of("1.746721937599626818e9"), 1746721937599626818);
  EXPECT_EQ(ns_of("174672193762462681.8e-8"), 1746721937624626818);
  EXPECT_EQ(ns_of("-0.5"), -500000000);
  EXPECT_EQ(ns_of("+3"), 3000000000);
  EXPECT_EQ(ns_of("0"), 0);
  EXPECT_EQ(ns_of("0.000"), 0);
  EXPECT_EQ(ns_of("1E2"), 100000000000);
  EXPECT_EQ(ns_of("7 "), 7000000000);  // simdjson's raw token keeps trailing spaces
}

TEST(ExactTime, DigitsPastTheNanosecondRoundToNearestTiesToEven) {
  EXPECT_EQ(ns_of("0.30000000000000004"), 300000000);  // a Python float sum
  EXPECT_EQ(ns_of("0.0000000015"), 2);                 // tie: to even
  EXPECT_EQ(ns_of("0.0000000025"), 2);
  EXPECT_EQ(ns_of("0.00000000250001"), 3);
  EXPECT_EQ(ns_of("0.0000000004999"), 0);
  EXPECT_EQ(ns_of("1e-30"), 0);
  EXPECT_EQ(ns_of("0.9999999995"), 1000000000);  // carries into the seconds
}

TEST(ExactTime, OutOfRangeAndMalformedAreNamed) {
  int64_t ns = 0;
  EXPECT_EQ(parse_seconds("1e400", ns), SecondsStatus::OutOfRange);
  EXPECT_EQ(parse_seconds("9223372036.854775808", ns), SecondsStatus::OutOfRange);
  EXPECT_EQ(parse_seconds("9223372036.854775807", ns), SecondsStatus::Ok);
  EXPECT_EQ(ns, INT64_MAX);
  EXPECT_EQ(parse_seconds("-9223372036.854775808", ns), SecondsStatus::Ok);
  EXPECT_EQ(ns, INT64_MIN);
  for (const char* bad : {"", "-", ".5x", "1.", "e5", "1e", "1e+", "abc", "1..2", "0x10", "NaN", "inf"})
    EXPECT_EQ(parse_seconds(bad, ns), SecondsStatus::Malformed) << bad;
}

TEST(ExactTime, PrintedWithoutExponentAndAtMostNineDecimals) {
  EXPECT_EQ(seconds_text(1746721937599626818), "1746721937.599626818");
  EXPECT_EQ(seconds_text(1746721937500000000), "1746721937.5");
  EXPECT_EQ(seconds_text(5000000000), "5");
  EXPECT_EQ(seconds_text(0), "0");
  EXPECT_EQ(seconds_text(1), "0.000000001");
  EXPECT_EQ(seconds_text(-500000000), "-0.5");
  EXPECT_EQ(seconds_text(INT64_MIN), "-9223372036.854775808");
}

TEST(ExactTime, EveryNanosecondRoundTrips) {
  std::mt19937_64 rng(7);
  for (int i = 0; i < 100000; ++i) {
    const auto ns = static_cast<int64_t>(rng());
    int64_t back = 0;
    ASSERT_EQ(parse_seconds(seconds_text(ns), back), SecondsStatus::Ok);
    ASSERT_EQ(back, ns);
  }
}

TEST(ExactTime, LiteralsHeldInDoublesComeBackAsTheirNanoseconds) {
  EXPECT_EQ(rvc::spec::seconds_to_ns(0.025), 25000000.0);
  EXPECT_EQ(rvc::spec::seconds_to_ns(0.1), 100000000.0);
  EXPECT_EQ(rvc::spec::seconds_to_ns(1e-9), 1.0);
  EXPECT_EQ(rvc::spec::seconds_to_ns(86400.000000001), 86400000000001.0);
}
