// What `rvc hz` shows of its topics each period: a table like `ros2 topic
// hz`'s, one JSON object per topic (--json), and one DiagnosticStatus per
// topic for /diagnostics (docs/cli.md, "rvc hz", lists every field).
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "io/diagnostics.hpp"
#include "runtime/topic_rate.hpp"

namespace rvc::cli {

// One topic as a report sees it.
struct HzRow {
  const std::string* uri;
  const runtime::TopicRate* stats;
  uint64_t rejected = 0;
  uint64_t received() const { return stats->received() + rejected; }
};

// `header`: print the column names first (the first report, the final one).
void print_hz_table(std::FILE* out, const std::vector<HzRow>& rows, double now, bool final, bool header);
void print_hz_json(std::FILE* out, const std::vector<HzRow>& rows, double now, bool final);
io::DiagStatus hz_status(const HzRow& row, double now);

}  // namespace rvc::cli
