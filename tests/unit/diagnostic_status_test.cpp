// The monitor's /diagnostics mapping (runtime/diagnostic_status.hpp and
// diagnostics_output.hpp): levels per property (OK, WARN/ERROR as marked,
// STALE), the monitor's own status, the key/value pairs, when an array goes
// out; and the properties file's `level:` key.
#include "runtime/diagnostic_status.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <chrono>
#include <string>
#include <unistd.h>

#include "io/properties_file.hpp"
#include "runtime/diagnostics_output.hpp"

namespace rvc::runtime {
namespace {

const DiagIdentity kWho{"m1", "host-a"};

LoopHealth one_input(double silent_for, uint64_t received = 10) {
  LoopHealth h;
  h.received = received;
  h.checked = received;
  h.inputs.push_back({"zenoh:a", received, silent_for});
  return h;
}

std::string value_of(const io::DiagStatus& s, const std::string& key) {
  for (const auto& [k, v] : s.values)
    if (k == key) return v;
  ADD_FAILURE() << "no value '" << key << "' in " << s.name;
  return {};
}

PropertyState violated(io::DiagLevel on_violation) {
  PropertyState p{"p1", "historically({a})", on_violation};
  p.has_verdict = true;
  p.value = false;
  p.verdict_time = 12.5;
  p.verdicts = 2;
  p.violations = 1;
  return p;
}

TEST(DiagnosticStatus, HoldingPropertyIsOkWithItsSpecAndCounters) {
  PropertyState p{"p1", "historically({a})"};
  p.has_verdict = true;
  p.value = true;
  p.verdict_time = 3;
  p.verdicts = 1;
  LoopHealth h = one_input(0.2);
  h.rejected = 4;
  h.dropped = 1;
  const io::DiagStatus s = property_status(kWho, p, h, 5);
  EXPECT_EQ(s.level, io::DiagLevel::Ok);
  EXPECT_EQ(s.name, "rvc: m1/p1");
  EXPECT_EQ(s.hardware_id, "host-a");
  EXPECT_EQ(s.message, "holds");
  EXPECT_EQ(value_of(s, "spec"), "historically({a})");
  EXPECT_EQ(value_of(s, "verdict"), "true");
  EXPECT_EQ(value_of(s, "verdict_time"), "3");
  EXPECT_EQ(value_of(s, "violations"), "0");
  EXPECT_EQ(value_of(s, "received"), "10");
  EXPECT_EQ(value_of(s, "rejected"), "4");
  EXPECT_EQ(value_of(s, "dropped"), "1");
}

TEST(DiagnosticStatus, ViolationIsErrorByDefaultAndWarnWhenMarked) {
  const io::DiagStatus error = property_status(kWho, violated(io::DiagLevel::Error), one_input(0), 5);
  EXPECT_EQ(error.level, io::DiagLevel::Error);
  EXPECT_EQ(error.message, "violated");
  EXPECT_EQ(value_of(error, "verdict"), "false");
  EXPECT_EQ(value_of(error, "verdict_time"), "12.5");
  EXPECT_EQ(value_of(error, "violations"), "1");
  EXPECT_EQ(value_of(error, "on_violation"), "ERROR");
  const io::DiagStatus warn = property_status(kWho, violated(io::DiagLevel::Warn), one_input(0), 5);
  EXPECT_EQ(warn.level, io::DiagLevel::Warn);
  EXPECT_EQ(value_of(warn, "on_violation"), "WARN");
  EXPECT_EQ(PropertyState{}.on_violation, io::DiagLevel::Error);
}

TEST(DiagnosticStatus, StaleWhenAnInputIsSilentOrNoVerdictYet) {
  const io::DiagStatus silent = property_status(kWho, violated(io::DiagLevel::Error), one_input(6), 5);
  EXPECT_EQ(silent.level, io::DiagLevel::Stale);
  EXPECT_NE(silent.message.find("no message on zenoh:a"), std::string::npos) << silent.message;
  // Not yet past the limit; a limit of 0 never makes it stale.
  EXPECT_EQ(property_status(kWho, violated(io::DiagLevel::Error), one_input(4.9), 5).level, io::DiagLevel::Error);
  EXPECT_EQ(property_status(kWho, violated(io::DiagLevel::Error), one_input(1e6), 0).level, io::DiagLevel::Error);
  const io::DiagStatus none = property_status(kWho, PropertyState{"p2", "{a}"}, one_input(0), 5);
  EXPECT_EQ(none.level, io::DiagLevel::Stale);
  EXPECT_EQ(value_of(none, "verdict"), "none");
}

TEST(DiagnosticStatus, MonitorWarnsOnNewRejectionsAndSilentInputs) {
  LoopHealth before = one_input(0.1);
  LoopHealth now = one_input(0.1);
  io::DiagStatus s = monitor_status(kWho, now, before, 5);
  EXPECT_EQ(s.name, "rvc: m1/monitor");
  EXPECT_EQ(s.level, io::DiagLevel::Ok);
  EXPECT_EQ(value_of(s, "input zenoh:a received"), "10");
  now.rejected = 3;
  s = monitor_status(kWho, now, before, 5);
  EXPECT_EQ(s.level, io::DiagLevel::Warn);
  EXPECT_NE(s.message.find("3 rejected"), std::string::npos) << s.message;
  EXPECT_EQ(value_of(s, "rejected"), "3");
  // The same total as at the previous status: nothing new, OK again.
  EXPECT_EQ(monitor_status(kWho, now, now, 5).level, io::DiagLevel::Ok);
  now.gaps = 2;
  EXPECT_EQ(monitor_status(kWho, now, before, 5).level, io::DiagLevel::Warn);
  const io::DiagStatus silent = monitor_status(kWho, one_input(9), one_input(9), 5);
  EXPECT_EQ(silent.level, io::DiagLevel::Warn);
  EXPECT_NE(silent.message.find("no message on zenoh:a"), std::string::npos) << silent.message;
}

TEST(DiagnosticStatus, ViolationLevelNames) {
  EXPECT_EQ(parse_violation_level("warn"), io::DiagLevel::Warn);
  EXPECT_EQ(parse_violation_level("WARN"), io::DiagLevel::Warn);
  EXPECT_EQ(parse_violation_level("Error"), io::DiagLevel::Error);
  EXPECT_THROW(parse_violation_level("fatal"), std::invalid_argument);
  EXPECT_THROW(parse_violation_level(""), std::invalid_argument);
}

// A sink that keeps what it is given (and the sequence numbers).
struct CapturingSink : transport::Sink {
  std::vector<std::string>* got;
  std::vector<uint64_t>* seqs;
  explicit CapturingSink(std::vector<std::string>* g, std::vector<uint64_t>* s = nullptr) : got(g), seqs(s) {}
  void put(std::string_view payload, uint64_t seq) override {
    got->emplace_back(payload);
    if (seqs) seqs->push_back(seq);
  }
  void put_eos(uint64_t) override {}
};

TEST(DiagnosticsOutput, EverySinkNumbersTheArraysOneByOne) {
  // A Zenoh reader counts gaps by these numbers: each sink's must run 1, 2, 3 with no holes.
  std::vector<std::string> got_a, got_b;
  std::vector<uint64_t> seq_a, seq_b;
  std::vector<DiagnosticsOutput::Output> outputs;
  outputs.push_back({std::make_unique<CapturingSink>(&got_a, &seq_a), false});
  outputs.push_back({std::make_unique<CapturingSink>(&got_b, &seq_b), true});
  DiagnosticsOptions options;
  options.identity = kWho;
  DiagnosticsOutput out(std::move(outputs), {{"p1", "{a}"}}, options);
  const auto start = std::chrono::steady_clock::now() - std::chrono::seconds(10);
  for (int i = 0; i < 3; ++i) out.on_health(one_input(0), start + std::chrono::seconds(2 * i));
  EXPECT_EQ(seq_a, (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(seq_b, (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_EQ(got_a.at(0).front(), '{');   // JSON
  EXPECT_EQ(got_b.at(0).substr(0, 2), std::string("\0\1", 2));  // CDR, little endian
}

TEST(DiagnosticsOutput, PublishesAtOnceOnALevelChangeOnly) {
  std::vector<std::string> got;
  std::vector<DiagnosticsOutput::Output> outputs;
  outputs.push_back({std::make_unique<CapturingSink>(&got), false});
  DiagnosticsOptions options;
  options.identity = kWho;
  options.levels["p1"] = io::DiagLevel::Warn;
  options.period = 1;
  options.stale_after = 5;
  DiagnosticsOutput out(std::move(outputs), {{"p1", "{a}"}, {"p2", "{b}"}}, options);
  const std::string p1 = "p1";
  out.on_verdict({p1, 1, true});  // before the loop's first tick: no counters yet, nothing sent
  EXPECT_EQ(got.size(), 0u);
  // The ticks' times, in the past: a verdict's array is timed by the real clock, after them.
  const auto start = std::chrono::steady_clock::now() - std::chrono::seconds(10);
  out.on_health(one_input(0), start);  // the first tick: the period is due
  ASSERT_EQ(got.size(), 1u);
  EXPECT_NE(got[0].find("\"name\":\"rvc: m1/p1\",\"message\":\"holds\""), std::string::npos) << got[0];
  out.on_health(one_input(0), start + std::chrono::milliseconds(500));  // period 1 s: not yet, nothing changed
  EXPECT_EQ(got.size(), 1u);
  out.on_health(one_input(0), start + std::chrono::milliseconds(1001));  // the period
  EXPECT_EQ(got.size(), 2u);
  out.on_health(one_input(6), start + std::chrono::milliseconds(1200));  // silent past stale_after: STALE at once
  ASSERT_EQ(got.size(), 3u);
  EXPECT_NE(got[2].find("\"level\":3,\"name\":\"rvc: m1/p1\""), std::string::npos) << got[2];
  out.on_health(one_input(0), start + std::chrono::milliseconds(1300));  // a message again: OK
  ASSERT_EQ(got.size(), 4u);
  out.on_verdict({p1, 2, true});  // still OK: nothing new to say before the period
  EXPECT_EQ(got.size(), 4u);
  // More than 100 ms after the last array (the rate limit): a change goes out at once.
  out.on_verdict({p1, 3, false});  // OK -> WARN (marked warn)
  ASSERT_EQ(got.size(), 5u);
  EXPECT_NE(got[4].find("\"level\":1,\"name\":\"rvc: m1/p1\",\"message\":\"violated\""), std::string::npos) << got[4];
  EXPECT_NE(got[4].find("{\"key\":\"violations\",\"value\":\"1\"}"), std::string::npos) << got[4];
  const std::string other = "not-a-property";
  out.on_verdict({other, 4, false});
  EXPECT_EQ(got.size(), 5u);
}

std::string write_temp(const std::string& text) {
  char name[] = "/tmp/rvc_levels_XXXXXX";
  const int fd = mkstemp(name);
  EXPECT_GE(fd, 0);
  std::ofstream(name) << text;
  close(fd);
  return name;
}

TEST(PropertiesFileLevel, LevelKeyIsReadAndChecked) {
  const std::string path = write_temp(
      "properties:\n  - name: a\n    spec: historically({x})\n    level: warn\n  - spec: '{y}'\n    level: ERROR\n"
      "  - name: c\n    spec: '{z}'\n");
  EXPECT_EQ(io::load_properties(path).size(), 3u);
  const auto levels = io::load_property_levels(path);
  ASSERT_EQ(levels.size(), 2u);
  EXPECT_EQ(levels[0].name, "a");
  EXPECT_EQ(levels[0].level, "warn");
  EXPECT_EQ(levels[1].name, "p2");
  EXPECT_EQ(levels[1].level, "error");
  std::remove(path.c_str());
  const std::string bad = write_temp("properties:\n  - name: a\n    spec: '{x}'\n    level: fatal\n");
  try {
    io::load_properties(bad);
    ADD_FAILURE() << "level: fatal accepted";
  } catch (const io::PropertiesError& e) {
    EXPECT_NE(std::string(e.what()).find("level 'fatal': expected warn or error"), std::string::npos) << e.what();
  }
  std::remove(bad.c_str());
}

}  // namespace
}  // namespace rvc::runtime
