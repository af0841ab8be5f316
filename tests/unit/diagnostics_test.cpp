// /diagnostics encoding (io/diagnostics.hpp) against bytes worked out by hand
// from the XCDR1 rules (every primitive aligned to its size from the end of
// the 4-byte header; strings as length-with-NUL, bytes, NUL).
#include "io/diagnostics.hpp"

#include <gtest/gtest.h>

#include <string>

namespace rvc::io {
namespace {

std::string bytes(std::initializer_list<int> b) {
  std::string s;
  for (int x : b) s.push_back(static_cast<char>(x));
  return s;
}

TEST(Diagnostics, CdrMatchesHandComputedBytes) {
  DiagStatus s;
  s.level = DiagLevel::Warn;
  s.name = "a";
  s.hardware_id = "h";
  s.values = {{"k", "v"}};
  const std::string want = bytes({
      0x00, 0x01, 0x00, 0x00,                          // header: CDR little endian
      0x01, 0x00, 0x00, 0x00,                          // 0: stamp.sec = 1
      0x00, 0x65, 0xCD, 0x1D,                          // 4: stamp.nanosec = 500000000
      0x01, 0x00, 0x00, 0x00, 0x00,                    // 8: frame_id "" (length 1, NUL)
      0x00, 0x00, 0x00,                                // 13: pad to 16
      0x01, 0x00, 0x00, 0x00,                          // 16: one status
      0x01,                                            // 20: level WARN
      0x00, 0x00, 0x00,                                // 21: pad to 24
      0x02, 0x00, 0x00, 0x00, 'a', 0x00,               // 24: name "a"
      0x00, 0x00,                                      // 30: pad to 32
      0x01, 0x00, 0x00, 0x00, 0x00,                    // 32: message ""
      0x00, 0x00, 0x00,                                // 37: pad to 40
      0x02, 0x00, 0x00, 0x00, 'h', 0x00,               // 40: hardware_id "h"
      0x00, 0x00,                                      // 46: pad to 48
      0x01, 0x00, 0x00, 0x00,                          // 48: one key/value
      0x02, 0x00, 0x00, 0x00, 'k', 0x00,               // 52: key "k"
      0x00, 0x00,                                      // 58: pad to 60
      0x02, 0x00, 0x00, 0x00, 'v', 0x00,               // 60: value "v"
  });
  const std::string got = diagnostic_array_cdr(1.5, {s});
  ASSERT_GE(got.size(), want.size());
  EXPECT_EQ(got.substr(0, want.size()), want);
  EXPECT_LE(got.size() - want.size(), 3u);  // only padding after the last field
  for (size_t i = want.size(); i < got.size(); ++i) EXPECT_EQ(got[i], '\0');
}

TEST(Diagnostics, JsonNamesEveryField) {
  DiagStatus s;
  s.level = DiagLevel::Stale;
  s.name = "rvc: m/p\"q";
  s.message = "no message for 2 s";
  EXPECT_EQ(diagnostic_array_json(2.25, {s}, "base"),
            R"({"header":{"stamp":{"sec":2,"nanosec":250000000},"frame_id":"base"},"status":[{"level":3,)"
            R"("name":"rvc: m/p\"q","message":"no message for 2 s","hardware_id":"","values":[]}]})");
}

TEST(Diagnostics, StampsRoundToTheNanosecondWithoutOverflow) {
  const std::string js = diagnostic_array_json(4.9999999999, {});
  EXPECT_NE(js.find(R"("sec":5,"nanosec":0)"), std::string::npos) << js;
  EXPECT_NE(diagnostic_array_json(-1, {}).find(R"("sec":0,"nanosec":0)"), std::string::npos);
}

TEST(Diagnostics, LevelNames) {
  EXPECT_STREQ(to_string(DiagLevel::Ok), "OK");
  EXPECT_STREQ(to_string(DiagLevel::Warn), "WARN");
  EXPECT_STREQ(to_string(DiagLevel::Error), "ERROR");
  EXPECT_STREQ(to_string(DiagLevel::Stale), "STALE");
}

}  // namespace
}  // namespace rvc::io
