// Typed input writes only the fields the properties read (io::CdrSelection),
// but still reads and checks every field: a selection changes what is written,
// never what is accepted, and never a verdict.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "runtime/pipeline.hpp"

namespace rvc::io {
namespace {

const char* kStatus = "tier4_external_api_msgs/msg/VehicleStatusStamped";
const char* kJson =
    R"({"stamp":{"sec":5,"nanosec":7},"status":{"twist":{"linear":{"x":1.5,"y":0,"z":0},)"
    R"("angular":{"x":0,"y":0,"z":-0.25}},"steering":{"data":0.5},"turn_signal":{"data":3},"gear_shift":{"data":2}}})";

std::string encode(const msg::MessageType& type, const std::string& json) {
  std::string sample, error;
  EXPECT_TRUE(json_to_cdr(type, json, sample, error)) << error;
  return sample;
}

std::string decode(const msg::MessageType& type, const std::string& sample, const CdrSelection* s, bool& ok) {
  std::string out;
  CdrError e;
  ok = cdr_to_json(type, sample, out, e, s);
  return out;
}

TEST(CdrSelection, WritesOnlyTheSelectedFields) {
  msg::TypeRegistry reg;
  const auto& type = reg.resolve(kStatus);
  const std::string sample = encode(type, kJson);
  CdrSelection s;
  s.add({"status", "twist", "linear", "x"});
  s.add({"status", "gear_shift"});  // a whole nested message
  bool ok = false;
  EXPECT_EQ(decode(type, sample, &s, ok), R"({"status":{"twist":{"linear":{"x":1.5}},"gear_shift":{"data":2}}})");
  EXPECT_TRUE(ok);
  EXPECT_EQ(decode(type, sample, nullptr, ok), kJson);
  CdrSelection nothing;
  EXPECT_EQ(decode(type, sample, &nothing, ok), "{}");
  CdrSelection all;
  all.add_all();
  EXPECT_EQ(decode(type, sample, &all, ok), kJson);
}

TEST(CdrSelection, UnselectedFieldsAreStillChecked) {
  msg::TypeRegistry reg;
  reg.add_definition("t_msgs/msg/T", "bool flag\nstring name\nfloat64 x\n", "test");
  const auto& type = reg.resolve("t_msgs/msg/T");
  std::string sample = encode(type, R"({"flag":true,"name":"ab","x":2})");
  CdrSelection s;
  s.add({"x"});
  bool ok = false;
  EXPECT_EQ(decode(type, sample, &s, ok), R"({"x":2})");
  EXPECT_TRUE(ok);
  std::string bad_bool = sample;
  bad_bool[4] = 2;  // the bool holds 2
  decode(type, bad_bool, &s, ok);
  EXPECT_FALSE(ok);
  std::string bad_utf8 = sample;
  bad_utf8[12] = '\xff';  // a byte of "ab"
  decode(type, bad_utf8, &s, ok);
  EXPECT_FALSE(ok);
  decode(type, sample.substr(0, sample.size() - 4), &s, ok);  // truncated
  EXPECT_FALSE(ok);
}

TEST(CdrSelection, PipelineVerdictsEqualTheJsonPath) {
  msg::TypeRegistry reg;
  const auto& type = reg.resolve(kStatus);
  const std::vector<engine::PropertySpec> props = {
      {"p", "{status.gear_shift.data == 2} -> {status.twist.linear.x < 3}"},
      {"q", "once[0:2]{status.turn_signal.data == 3}"}};
  std::vector<std::string> json;
  for (int i = 0; i < 12; ++i)
    json.push_back(R"({"stamp":{"sec":)" + std::to_string(i) + R"(,"nanosec":0},"status":{"twist":{"linear":{"x":)" +
                   std::to_string(i % 5) + R"(,"y":0,"z":0},"angular":{"x":0,"y":0,"z":0}},"steering":{"data":0},)" +
                   R"("turn_signal":{"data":)" + std::to_string(i % 4) + R"(},"gear_shift":{"data":)" +
                   std::to_string(i % 3) + "}}}");
  auto run = [&](bool typed) {
    runtime::PipelineOptions o;
    o.emit_all = true;
    o.type = typed ? &type : nullptr;
    std::vector<std::string> out;
    runtime::Pipeline p(props, o, [&](const engine::Verdict& v) {
      out.push_back(v.property + std::to_string(v.time) + (v.value ? "T" : "F"));
    });
    uint64_t seq = 0;
    for (const auto& j : json) p.feed(typed ? encode(type, j) : j, ++seq);
    EXPECT_EQ(p.stats().rejected, 0u);
    return out;
  };
  const auto from_json = run(false);
  EXPECT_EQ(run(true), from_json);
  EXPECT_EQ(from_json.size(), 24u);
}

}  // namespace
}  // namespace rvc::io
