// Numbers compare exactly (spec/exact_number.hpp): 64-bit integers never
// round through double, neither against each other nor against a double.
// Expected values are written by hand (or are Python's exact int/float
// comparisons, noted where used); the JSON cases run with layouts on and off,
// as file lines and as payloads, so both readers of a number are covered.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "io/jsonl_reader.hpp"
#include "msg/msg_parser.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"
#include "spec/exact_number.hpp"
#include "test_util.hpp"

namespace rvc {
namespace {

using spec::ExactInt;

ExactInt big(int64_t v) { return spec::exact_of(v); }
ExactInt ubig(uint64_t v) { return spec::exact_of(v); }
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(ExactNumber, IntegersBeyondTwoTo53AreKeptOnlyThere) {
  EXPECT_EQ(big(9007199254740992).kind, ExactInt::None);  // 2^53: a double holds it
  EXPECT_EQ(big(9007199254740993).kind, ExactInt::Signed);
  EXPECT_EQ(big(-9007199254740993).kind, ExactInt::Signed);
  EXPECT_EQ(ubig(9223372036854775808u).kind, ExactInt::Unsigned);
  EXPECT_EQ(ubig(9223372036854775807u).kind, ExactInt::Signed);
}

TEST(ExactNumber, OrdersAsTheRealValues) {
  const double two63 = 9223372036854775808.0, two53 = 9007199254740992.0;
  // int64 max against 2^63 (its rounded double): less, not equal.
  EXPECT_EQ(spec::order_int_double(big(INT64_MAX), two63), spec::Less);
  EXPECT_EQ(spec::order_int_double(ubig(uint64_t{1} << 63), two63), spec::Equal);
  EXPECT_EQ(spec::order_int_double(ubig(UINT64_MAX), 18446744073709551616.0), spec::Less);
  EXPECT_EQ(spec::order_int_double(ubig(UINT64_MAX), 18446744073709549568.0), spec::Greater);  // 2^64 - 2048
  EXPECT_EQ(spec::order_int_double(big(9007199254740993), two53), spec::Greater);
  EXPECT_EQ(spec::order_int_double(big(9007199254740993), 9007199254740994.0), spec::Less);
  EXPECT_EQ(spec::order_int_double(big(-9007199254740993), -two53), spec::Less);
  EXPECT_EQ(spec::order_int_double(big(INT64_MIN), -two63), spec::Equal);
  EXPECT_EQ(spec::order_int_double(big(INT64_MIN), -two63 - 2048), spec::Greater);
  EXPECT_EQ(spec::order_int_double(big(INT64_MIN + 1), -two63), spec::Greater);
  EXPECT_EQ(spec::order_int_double(big(INT64_MAX), kInf), spec::Less);
  EXPECT_EQ(spec::order_int_double(ubig(UINT64_MAX), -kInf), spec::Greater);
  EXPECT_EQ(spec::order_int_double(big(INT64_MAX), kNaN), spec::Unordered);
  EXPECT_EQ(spec::order_int_double(big(INT64_MAX), 1e300), spec::Less);
  EXPECT_EQ(spec::order_int_double(big(-9007199254740993), -9007199254740992.5), spec::Less);  // -2^53 - 0.5 is no double: -2^53
  EXPECT_EQ(spec::order_ints(big(INT64_MAX), ubig(uint64_t{1} << 63)), spec::Less);
  EXPECT_EQ(spec::order_ints(big(INT64_MIN), big(INT64_MIN + 1)), spec::Less);
  EXPECT_EQ(spec::order_numbers(two63, {}, two63, big(INT64_MAX)), spec::Greater);
  EXPECT_EQ(spec::order_numbers(-0.0, {}, 0.0, {}), spec::Equal);
}

TEST(ExactNumber, IntegerLiteralsReadExactly) {
  double d;
  ExactInt e;
  ASSERT_TRUE(spec::integer_literal("18446744073709551615", d, e));
  EXPECT_EQ(e.kind, ExactInt::Unsigned);
  EXPECT_EQ(e.bits, UINT64_MAX);
  EXPECT_EQ(d, 18446744073709551616.0);
  ASSERT_TRUE(spec::integer_literal("-9223372036854775808", d, e));
  EXPECT_EQ(static_cast<int64_t>(e.bits), INT64_MIN);
  ASSERT_TRUE(spec::integer_literal("+9007199254740993", d, e));
  EXPECT_EQ(static_cast<int64_t>(e.bits), 9007199254740993);
  EXPECT_FALSE(spec::integer_literal("18446744073709551616", d, e));  // beyond 64 bits: the caller's double
  EXPECT_FALSE(spec::integer_literal("-9223372036854775809", d, e));
  EXPECT_FALSE(spec::integer_literal("1e3", d, e));
  EXPECT_FALSE(spec::integer_literal("1.0", d, e));
}

// Every verdict (--all) of `spec` over `lines`, through the pipeline:
// [layouts off, on] x [a file, payloads] must agree; returns one of them.
std::string verdicts(const std::string& spec, const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  std::vector<std::string> runs;
  for (bool layouts : {false, true}) {
    for (bool payloads : {false, true}) {
      runtime::PipelineOptions options;
      options.emit_all = true;
      options.layouts = layouts;
      std::string out;
      testing::internal::CaptureStderr();
      {
        runtime::Pipeline p({{"p", spec}}, options, [&](const engine::Verdict& v) { out += v.value ? '1' : '0'; });
        if (payloads) {
          uint64_t seq = 0;
          for (const auto& l : lines) p.feed(l, ++seq);
        } else {
          test::TempFile f(text);
          const int fd = ::open(f.path().c_str(), O_RDONLY);
          std::string error;
          EXPECT_TRUE(io::read_jsonl(fd, p, io::ReaderOptions{}, error)) << error;
          ::close(fd);
        }
        p.finish_report();
      }
      const std::string errors = testing::internal::GetCapturedStderr();
      EXPECT_EQ(errors, "") << spec;
      runs.push_back(out);
    }
  }
  for (const auto& r : runs) EXPECT_EQ(r, runs[0]) << spec;
  return runs[0];
}

// The issue's three examples, each line repeated so that layouts learn it.
TEST(ExactNumber, JsonIntegersBeyondTwoTo53CompareExactly) {
  const std::vector<std::string> two63 = {R"({"u":9223372036854775808})", R"({"u":9223372036854775808})",
                                          R"({"u":9223372036854775807})", R"({"u":9223372036854775807})"};
  EXPECT_EQ(verdicts("{u == 9223372036854775807}", two63), "0011");
  EXPECT_EQ(verdicts("{u < 9223372036854775808}", two63), "0011");
  const std::vector<std::string> stamps = {R"({"data":1700000000000000001})", R"({"data":1700000000000000001})",
                                           R"({"data":1700000000000000000})", R"({"data":1699999999999999999})"};
  EXPECT_EQ(verdicts("{data > 1700000000000000000}", stamps), "1100");
  EXPECT_EQ(verdicts("{data >= 1700000000000000000}", stamps), "1110");
  const std::vector<std::string> two53 = {R"({"data":9007199254740992})", R"({"data":9007199254740992})",
                                          R"({"data":9007199254740993})", R"({"data":9007199254740993.0})"};
  // The last is a float literal: the double 2^53 (as Python's json reads it).
  EXPECT_EQ(verdicts("{data == 9007199254740993}", two53), "0010");
  EXPECT_EQ(verdicts("{data != 9007199254740992}", two53), "0010");
  // 2^64 - 1 against a float literal: 1.8446744073709552e19 is 2^64.
  const std::vector<std::string> max = {R"({"u":18446744073709551615})", R"({"u":18446744073709551615})"};
  EXPECT_EQ(verdicts("{u < 1.8446744073709552e19}", max), "11");
  EXPECT_EQ(verdicts("{u == 18446744073709551615}", max), "11");
  EXPECT_EQ(verdicts("{u == 18446744073709551614}", max), "00");
}

TEST(ExactNumber, LiteralsOfTwoIntegersAreTwoAtoms) {
  // Their canonical texts kept every digit: once shared as one atom, the second test read the first's value.
  const std::vector<std::string> lines = {R"({"u":9223372036854775807})", R"({"u":9223372036854775806})"};
  EXPECT_EQ(verdicts("{u == 9223372036854775807} && !{u == 9223372036854775806}", lines), "10");
}

TEST(ExactNumber, NonFiniteJsonWordsAreNumbers) {
  // As `rvc echo` writes a NaN or infinite float; IEEE 754: NaN compares false but for !=.
  const std::vector<std::string> lines = {R"({"x":NaN})", R"({"x":Infinity})", R"({"x":-Infinity})", R"({"x":1})"};
  EXPECT_EQ(verdicts("{x > 0}", lines), "0101");
  EXPECT_EQ(verdicts("{x != 1}", lines), "1110");
  EXPECT_EQ(verdicts("{x <= 1}", lines), "0011");
  EXPECT_EQ(verdicts("{x}", lines), "1111");  // non-zero
  // In a field no test reads, and in arrays: well-formed, the message counts.
  EXPECT_EQ(verdicts("{y}", {R"({"x":NaN,"y":true,"z":[Infinity,-Infinity]})"}), "1");
}

// Typed: int64/uint64 fields compare exactly too (CdrDecoder).
TEST(ExactNumber, TypedIntegersCompareExactly) {
  msg::TypeRegistry registry;
  registry.add_definition("exact_msgs/msg/Nums", "int64 i\nuint64 u\nuint64 BIG=18446744073709551615\n", "test");
  const msg::MessageType& type = registry.resolve("exact_msgs/msg/Nums");
  auto sample = [&](const std::string& json) {
    std::string out, error;
    EXPECT_TRUE(io::json_to_cdr(type, json, out, error)) << error;
    return out;
  };
  struct Case {
    std::string spec, expected;
  };
  const std::vector<std::string> samples = {sample(R"({"i":9223372036854775807,"u":9223372036854775808})"),
                                            sample(R"({"i":-9223372036854775808,"u":18446744073709551614})"),
                                            sample(R"({"i":9007199254740993,"u":18446744073709551615})")};
  for (const Case& c : std::vector<Case>{{"{u == 9223372036854775808}", "100"},
                                         {"{i == 9223372036854775806}", "000"},
                                         {"{i > 9223372036854775806}", "100"},
                                         {"{i < -9223372036854775807}", "010"},
                                         {"{i == 9007199254740992}", "000"},
                                         {"{u == BIG}", "001"},
                                         {"{u != BIG}", "110"},
                                         {"{u >= 1.8446744073709552e19}", "000"}}) {
    runtime::PipelineOptions options;
    options.emit_all = true;
    options.type = &type;
    std::string out;
    runtime::Pipeline p({{"p", c.spec}}, options, [&](const engine::Verdict& v) { out += v.value ? '1' : '0'; });
    uint64_t seq = 0;
    for (const auto& s : samples) p.feed(s, ++seq);
    EXPECT_EQ(out, c.expected) << c.spec;
  }
}

}  // namespace
}  // namespace rvc
