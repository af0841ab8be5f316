// --output mcap: pieces: the CRC-32 the MCAP records carry, the file's frame
// (magic, Header, ..., Footer, magic) and the verdict's CDR sample, read back
// with rvc's type-driven CDR codec from the bundled rvc_msgs/msg/Verdict (the
// hand-written encoder and the .msg must agree). The whole file is checked
// against the mcap and rosbags packages in tests/cli/test_mcap_output.py.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "io/cdr_codec.hpp"
#include "io/verdict_writer.hpp"
#include "msg/type_registry.hpp"
#include "transport/mcap/mcap_writer.hpp"

namespace {

using rvc::transport::mcap::crc32;
using rvc::transport::mcap::McapWriter;

TEST(McapWriter, Crc32IsZlibs) {
  EXPECT_EQ(crc32("123456789"), 0xCBF43926u);  // the standard check value of CRC-32/ISO-HDLC
  EXPECT_EQ(crc32(""), 0u);
  EXPECT_EQ(crc32("6789", crc32("12345")), 0xCBF43926u);  // continued over pieces
}

TEST(McapWriter, FileStartsAndEndsWithMagicAndFooterPointsAtSummary) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  McapWriter w(f, "ros2", "rvc");
  const uint16_t s = w.add_schema("pkg/msg/T", "ros2msg", "int32 a\n");
  const uint16_t c = w.add_channel(s, "/t", "cdr");
  w.write_message(c, 1, 5, 5, std::string("\0\1\0\0\7\0\0\0", 8));
  w.close();
  w.close();  // idempotent
  std::string bytes(static_cast<size_t>(std::ftell(f)), '\0');
  std::rewind(f);
  ASSERT_EQ(std::fread(bytes.data(), 1, bytes.size(), f), bytes.size());
  std::fclose(f);
  const std::string magic("\x89MCAP0\r\n", 8);
  EXPECT_EQ(bytes.substr(0, 8), magic);
  EXPECT_EQ(bytes.substr(bytes.size() - 8), magic);
  EXPECT_EQ(bytes[8], '\x01');  // Header
  const std::string footer = bytes.substr(bytes.size() - 37, 29);
  EXPECT_EQ(footer[0], '\x02');
  uint64_t summary_start = 0;
  for (int i = 7; i >= 0; --i) summary_start = (summary_start << 8) | static_cast<unsigned char>(footer[9 + i]);
  ASSERT_LT(summary_start, bytes.size());
  EXPECT_EQ(bytes[summary_start], '\x03');      // the summary opens with the Schema group
  EXPECT_EQ(bytes[summary_start - 13], '\x0f');  // after DataEnd (opcode, length, CRC)
  EXPECT_EQ(w.message_count(), 1u);
}

TEST(VerdictCdr, ReadsBackThroughTheBundledDefinition) {
  rvc::msg::TypeRegistry registry;
  const auto& type = registry.resolve("rvc_msgs/msg/Verdict");
  std::string sample, json;
  const std::vector<std::string> why = {"first", "second line"};
  rvc::io::append_verdict_cdr(sample, 1.5, "p1", false, 1'700'000'001'250'000'000ull, -2.5, &why);
  rvc::io::CdrError error;
  ASSERT_TRUE(rvc::io::cdr_to_json(type, sample, json, error));
  EXPECT_EQ(json,
            "{\"time\":1.5,\"property\":\"p1\",\"value\":false,\"stamp\":{\"sec\":1700000001,\"nanosec\":250000000},"
            "\"robustness\":-2.5,\"explanation\":[\"first\",\"second line\"]}");
  // A Boolean verdict: robustness NaN, no explanation; the sample's size is exact (nothing left over).
  sample.clear();
  json.clear();
  rvc::io::append_verdict_cdr(sample, 3, "p_long_name", true, 3, std::numeric_limits<double>::quiet_NaN(), nullptr);
  ASSERT_TRUE(rvc::io::cdr_to_json(type, sample, json, error));
  EXPECT_NE(json.find("\"value\":true,\"stamp\":{\"sec\":0,\"nanosec\":3}"), std::string::npos) << json;
  EXPECT_NE(json.find("\"explanation\":[]"), std::string::npos) << json;
}

}  // namespace
