// libFuzzer harness: `rvc hz`'s input path on a file (src/cli/cmd_hz.cpp):
// what the file is (transport::binary_signature / is_bag, from its first
// bytes: a bag or a gzip file is refused, not read as lines), then each line's
// time field (runtime::TimeFieldReader) into the report schedule of
// --time-source stamps (runtime::StampSchedule) and the topic's statistics
// (runtime::TopicRate), a report at each boundary passed.
//
// Input: one options byte (the period and the window), then the file's bytes.
// Oracles beyond crashes: counts add up (lines = checked + refused); reports
// fall at strictly increasing times, never after the message that makes them
// due, and at most StampSchedule::kMaxCatchUp per message (a jump of the
// stamps is one report: 1e9 s of stamps printed a report per period and never
// ended); a report's rate and silence are no NaN. Under the harness's memory
// limits (resource_limits.hpp: -rss_limit_mb=2048 -malloc_limit_mb=512).
#include <sys/mman.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "lines.hpp"
#include "resource_limits.hpp"
#include "runtime/time_field_reader.hpp"
#include "runtime/topic_rate.hpp"
#include "transport/rosbag2/bag_reader.hpp"

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  rvc::fuzz::add_resource_limits(argc, argv);
  return 0;
}

namespace {

// What rvc hz decides from the first bytes, through the same path (a file).
bool refused_as_binary(std::string_view bytes) {
  const int fd = memfd_create("fuzz_hz", 0);
  if (fd < 0 || write(fd, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) __builtin_trap();
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  const bool binary = rvc::transport::is_bag(path) || !rvc::transport::binary_signature(path).empty();
  close(fd);
  return binary;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  constexpr double kPeriods[] = {0.01, 0.1, 1, 3600};
  const double period = kPeriods[data[0] & 3];
  rvc::runtime::RateThresholds thresholds;
  thresholds.window_size = 2 + ((data[0] >> 2) & 15);
  thresholds.timeout = (data[0] & 0x40) ? 0 : 1;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (refused_as_binary(text)) return 0;

  rvc::runtime::TimeFieldReader reader("time", nullptr);
  rvc::runtime::StampSchedule schedule(period);
  rvc::runtime::TopicRate stats(thresholds);
  uint64_t lines = 0, refused = 0;
  double last_report = -INFINITY;
  std::string error;
  rvc::fuzz::for_each_line(text, [&](std::string_view line) {
    ++lines;
    double time = 0;
    if (reader.read(line, time, error) != rvc::runtime::TimeFieldReader::Result::Ok ||
        (stats.any() && time < stats.last_arrival())) {
      ++refused;
      return;
    }
    const auto& due = schedule.step(time);
    if (due.reports.size() > rvc::runtime::StampSchedule::kMaxCatchUp) __builtin_trap();
    if (due.skipped > 0 && due.reports.size() != 1) __builtin_trap();  // a jump: one report
    for (double boundary : due.reports) {
      if (!(boundary > last_report) || boundary > time) __builtin_trap();
      last_report = boundary;
      const rvc::runtime::RateSummary s = stats.summary(boundary);
      if (std::isnan(s.rate) || std::isnan(s.silence)) __builtin_trap();
      (void)stats.state(boundary);
    }
    stats.add(time, std::nullopt);
  });
  if (stats.received() + refused != lines) __builtin_trap();
  return 0;
}
