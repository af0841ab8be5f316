// io::JsonObject / JsonArray: what they write must read back, value for
// value, through an independent parser (simdjson's DOM API).
#include <gtest/gtest.h>
#include <simdjson.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "io/json_writer.hpp"

namespace rvc::io {
namespace {

simdjson::dom::element parse(simdjson::dom::parser& parser, const std::string& json) {
  simdjson::dom::element e;
  auto err = parser.parse(json).get(e);
  EXPECT_FALSE(err) << simdjson::error_message(err) << " in " << json;
  return e;
}

TEST(JsonWriter, EveryControlCharacterReadsBack) {
  std::string all;
  for (int c = 0; c < 0x20; ++c) all.push_back(static_cast<char>(c));
  all += "\"\\/ plain ÄÖÜ € 😀";
  std::string json = JsonObject().add("s", all).str();
  for (char c : json) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << "raw control character in " << json;
  simdjson::dom::parser parser;
  std::string_view back;
  ASSERT_FALSE(parse(parser, json)["s"].get(back));
  EXPECT_EQ(std::string(back), all);
}

TEST(JsonWriter, NumbersReadBack) {
  const uint64_t big = std::numeric_limits<uint64_t>::max();
  const int64_t low = std::numeric_limits<int64_t>::min();
  std::string json = JsonObject()
                         .add("u", big)
                         .add("i", low)
                         .add("neg", -3)
                         .add("d", 0.1)
                         .add("tiny", 5e-324)
                         .add_fixed("f", 1795400000.1234567, 6)
                         .add("nan", std::nan(""))
                         .add("inf", std::numeric_limits<double>::infinity())
                         .add("t", true)
                         .str();
  simdjson::dom::parser parser;
  auto e = parse(parser, json);
  uint64_t u;
  int64_t i, neg;
  double d, tiny, f;
  bool t;
  ASSERT_FALSE(e["u"].get(u));
  EXPECT_EQ(u, big);
  ASSERT_FALSE(e["i"].get(i));
  EXPECT_EQ(i, low);
  ASSERT_FALSE(e["neg"].get(neg));
  EXPECT_EQ(neg, -3);
  ASSERT_FALSE(e["d"].get(d));
  EXPECT_EQ(d, 0.1);  // shortest round-trip form is exact
  ASSERT_FALSE(e["tiny"].get(tiny));
  EXPECT_EQ(tiny, 5e-324);
  ASSERT_FALSE(e["f"].get(f));
  EXPECT_NEAR(f, 1795400000.123457, 1e-6);
  EXPECT_TRUE(e["nan"].is_null());
  EXPECT_TRUE(e["inf"].is_null());
  ASSERT_FALSE(e["t"].get(t));
  EXPECT_TRUE(t);
  EXPECT_NE(json.find("\"f\":1795400000.123457"), std::string::npos) << json;
}

TEST(JsonWriter, NestedObjectsAndArrays) {
  JsonArray routes;
  routes.add(JsonObject().add("from", "dds:/a\"b").add("n", 1)).add(JsonObject().add("from", "zenoh:x\ny"));
  std::string json = JsonObject().add_raw("routes", routes.str()).add("empty", JsonObject()).str();
  simdjson::dom::parser parser;
  auto e = parse(parser, json);
  simdjson::dom::array a;
  ASSERT_FALSE(e["routes"].get(a));
  ASSERT_EQ(a.size(), 2u);
  std::string_view from;
  ASSERT_FALSE(a.at(0)["from"].get(from));
  EXPECT_EQ(from, "dds:/a\"b");
  ASSERT_FALSE(a.at(1)["from"].get(from));
  EXPECT_EQ(from, "zenoh:x\ny");
  simdjson::dom::object empty;
  ASSERT_FALSE(e["empty"].get(empty));
  EXPECT_EQ(empty.size(), 0u);
  EXPECT_EQ(JsonArray().str(), "[]");
}

}  // namespace
}  // namespace rvc::io
