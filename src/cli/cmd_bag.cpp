// rvc bag info: what a ROS 2 bag holds, as `ros2 bag info` prints it: its
// files and storage, compression, time span, and per topic the type, message
// count, serialization format and mean frequency. Reads MCAP files, rosbag2
// sqlite3 files and bag folders (transport/rosbag2), never modifying them.
#include <sys/stat.h>

#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <memory>
#include <string>

#include "cli/commands.hpp"
#include "io/json_writer.hpp"
#include "transport/rosbag2/bag_reader.hpp"

namespace rvc::cli {
namespace {

// "2020-04-02 22:23:55.112411371 UTC (1585866235.112411371)"
std::string format_time(uint64_t ns) {
  const time_t s = static_cast<time_t>(ns / 1000000000ULL);
  struct tm tm{};
  gmtime_r(&s, &tm);
  char buf[96];
  const size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M:%S", &tm);
  const uint64_t sec = ns / 1000000000u, frac = ns % 1000000000u;
  std::snprintf(buf + n, sizeof buf - n, ".%09" PRIu64 " UTC (%" PRIu64 ".%09" PRIu64 ")", frac, sec, frac);
  return buf;
}

std::string format_seconds(uint64_t ns) {
  char buf[48];
  const uint64_t sec = ns / 1000000000u, frac = ns % 1000000000u;
  std::snprintf(buf, sizeof buf, "%" PRIu64 ".%09" PRIu64 "s", sec, frac);
  return buf;
}

std::string format_size(uint64_t bytes) {
  char buf[48];
  if (bytes < 1024) std::snprintf(buf, sizeof buf, "%" PRIu64 " B", bytes);
  else if (bytes < 1024 * 1024) std::snprintf(buf, sizeof buf, "%.1f KiB", bytes / 1024.0);
  else if (bytes < 1024ULL * 1024 * 1024) std::snprintf(buf, sizeof buf, "%.1f MiB", bytes / 1048576.0);
  else std::snprintf(buf, sizeof buf, "%.2f GiB", bytes / 1073741824.0);
  return buf;
}

// Mean rate over the topic's own span: (n - 1) intervals; 0 below two messages.
double frequency(const transport::BagTopicInfo& t) {
  if (t.messages < 2 || t.last_time <= t.first_time) return 0;
  return static_cast<double>(t.messages - 1) / (static_cast<double>(t.last_time - t.first_time) * 1e-9);
}

struct BagCommand {
  std::string path;
  bool json = false;

  int info() {
    const std::string p = path.find(':') != std::string::npos && (path.rfind("bag:", 0) == 0 || path.rfind("mcap:", 0) == 0)
                              ? path.substr(path.find(':') + 1)
                              : path;
    if (!transport::is_bag(p)) transport::open_bag(p);  // throws, naming what the path is instead
    const transport::BagSummary s = transport::summarize_bag(p);
    uint64_t size = 0;
    for (const auto& f : s.files) {
      std::error_code ec;
      size += std::filesystem::file_size(f, ec);
    }
    const uint64_t duration = s.end - s.start;
    if (json) {
      io::JsonArray files, topics;
      for (const auto& f : s.files) {
        std::string quoted;
        io::append_json_string(quoted, f);
        files.add_raw(quoted);
      }
      for (const auto& t : s.topics)
        topics.add(io::JsonObject()
                       .add("name", t.name)
                       .add("type", t.type)
                       .add("serialization_format", t.encoding)
                       .add("messages", t.messages)
                       .add("first_ns", t.first_time)
                       .add("last_ns", t.last_time)
                       .add("frequency_hz", frequency(t))
                       .add("definition", !t.definition.empty()));
      io::JsonObject o;
      o.add("path", p).add("storage", s.storage);
      o.add_raw("files", files.str());
      o.add("size_bytes", size)
          .add("compression_format", s.compression_format)
          .add("compression_mode", s.compression_mode)
          .add("messages", s.messages)
          .add("start_ns", s.start)
          .add("end_ns", s.end)
          .add("duration_ns", duration);
      o.add_raw("topics", topics.str());
      if (!s.broken.empty()) o.add("broken", s.broken);
      if (!s.first_skipped.empty()) o.add("skipped", s.first_skipped);
      std::printf("%s\n", o.str().c_str());
    } else {
      std::string names;
      for (const auto& f : s.files) names += (names.empty() ? "" : "\n                   ") + f;
      std::printf("Files:             %s\n", names.c_str());
      std::printf("Bag size:          %s\n", format_size(size).c_str());
      std::printf("Storage id:        %s\n", s.storage.c_str());
      std::printf("Compression:       %s\n",
                  s.compression_format.empty() ? "none"
                                               : (s.compression_format + " (" + s.compression_mode + ")").c_str());
      std::printf("Duration:          %s\n", format_seconds(duration).c_str());
      std::printf("Start:             %s\n", s.messages ? format_time(s.start).c_str() : "-");
      std::printf("End:               %s\n", s.messages ? format_time(s.end).c_str() : "-");
      std::printf("Messages:          %" PRIu64 "\n", s.messages);
      size_t wname = 5, wtype = 4;
      for (const auto& t : s.topics) {
        wname = std::max(wname, t.name.size());
        wtype = std::max(wtype, t.type.size());
      }
      std::printf("Topic information: %zu topic%s\n", s.topics.size(), s.topics.size() == 1 ? "" : "s");
      std::printf("  %-*s  %-*s  %8s  %12s  %s\n", static_cast<int>(wname), "Topic", static_cast<int>(wtype), "Type",
                  "Count", "Frequency", "Format");
      for (const auto& t : s.topics) {
        char hz[32];
        if (t.messages >= 2) std::snprintf(hz, sizeof hz, "%.3f Hz", frequency(t));
        else std::snprintf(hz, sizeof hz, "-");
        std::printf("  %-*s  %-*s  %8" PRIu64 "  %12s  %s\n", static_cast<int>(wname), t.name.c_str(),
                    static_cast<int>(wtype), t.type.c_str(), t.messages, hz, t.encoding.c_str());
      }
    }
    // A damaged bag is listed as far as it could be read, and said so.
    if (!s.broken.empty()) std::fprintf(stderr, "rvc: %s (counts are up to there)\n", s.broken.c_str());
    if (!s.first_skipped.empty()) std::fprintf(stderr, "rvc: %s (a damaged record, not counted)\n", s.first_skipped.c_str());
    return s.broken.empty() && s.first_skipped.empty() ? kOk : kBadInput;
  }
};

}  // namespace

Runner register_bag(CLI::App& app) {
  auto cmd = std::make_shared<BagCommand>();
  CLI::App* sub = app.add_subcommand("bag", "ROS 2 bags (MCAP, rosbag2 sqlite3, bag folders): rvc bag info BAG");
  sub->require_subcommand(1);
  CLI::App* info = sub->add_subcommand("info", "What a bag holds: files, storage, compression, time span; per topic "
                                               "its type, count, frequency and format (as ros2 bag info)");
  info->add_option("bag", cmd->path, "The bag: a .mcap or .db3 file (zstd-compressed too) or a bag folder")->required();
  info->add_flag("--json", cmd->json, "One JSON object instead of the table");
  info->footer("Exit status: 0 the bag was read, 2 not a bag, 3 the bag is damaged (listed as far as it could be read).");
  return [cmd] { return cmd->info(); };
}

}  // namespace rvc::cli
