#include "runtime/diagnostic_status.hpp"

#include <cctype>
#include <cstdio>
#include <stdexcept>

namespace rvc::runtime {
namespace {

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", s);
  return buf;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

// The input silent the longest beyond `stale_after` (null if none is).
const LoopHealth::Input* silent_input(const LoopHealth& loop, double stale_after) {
  const LoopHealth::Input* worst = nullptr;
  if (stale_after <= 0) return nullptr;
  for (const auto& in : loop.inputs)
    if (in.silent_for > stale_after && (!worst || in.silent_for > worst->silent_for)) worst = &in;
  return worst;
}

void add_counters(io::DiagStatus& s, const LoopHealth& loop) {
  s.values.emplace_back("received", std::to_string(loop.received));
  s.values.emplace_back("checked", std::to_string(loop.checked));
  s.values.emplace_back("rejected", std::to_string(loop.rejected));
  s.values.emplace_back("dropped", std::to_string(loop.dropped));
}

}  // namespace

io::DiagLevel parse_violation_level(std::string_view text) {
  std::string lower;
  for (char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "warn" || lower == "warning") return io::DiagLevel::Warn;
  if (lower == "error") return io::DiagLevel::Error;
  throw std::invalid_argument("level '" + std::string(text) + "': expected warn or error");
}

io::DiagStatus property_status(const DiagIdentity& who, const PropertyState& p, const LoopHealth& loop,
                               double stale_after) {
  io::DiagStatus s;
  s.name = "rvc: " + who.monitor + "/" + p.name;
  s.hardware_id = who.hardware_id;
  if (const LoopHealth::Input* silent = silent_input(loop, stale_after)) {
    s.level = io::DiagLevel::Stale;
    s.message = "no message on " + silent->name + " for " + seconds(silent->silent_for) + " s";
  } else if (!p.has_verdict) {
    s.level = io::DiagLevel::Stale;
    s.message = "no verdict yet";
  } else if (p.value) {
    s.level = io::DiagLevel::Ok;
    s.message = "holds";
  } else {
    s.level = p.on_violation;
    s.message = "violated";
  }
  s.values.emplace_back("spec", p.spec);
  s.values.emplace_back("verdict", p.has_verdict ? (p.value ? "true" : "false") : "none");
  s.values.emplace_back("verdict_time", !p.has_verdict             ? std::string()
                                         : !p.verdict_time_text.empty() ? p.verdict_time_text
                                                                        : number(p.verdict_time));
  s.values.emplace_back("violations", std::to_string(p.violations));
  s.values.emplace_back("verdicts", std::to_string(p.verdicts));
  s.values.emplace_back("on_violation", io::to_string(p.on_violation));
  add_counters(s, loop);
  return s;
}

io::DiagStatus monitor_status(const DiagIdentity& who, const LoopHealth& now, const LoopHealth& since,
                              double stale_after) {
  io::DiagStatus s;
  s.name = "rvc: " + who.monitor + "/monitor";
  s.hardware_id = who.hardware_id;
  std::vector<std::string> problems;
  if (const LoopHealth::Input* silent = silent_input(now, stale_after))
    problems.push_back("no message on " + silent->name + " for " + seconds(silent->silent_for) + " s");
  auto grew = [&](uint64_t a, uint64_t b, const char* what) {
    if (a > b) problems.push_back(std::to_string(a - b) + " " + what);
  };
  grew(now.rejected, since.rejected, "rejected");
  grew(now.dropped, since.dropped, "dropped");
  grew(now.gaps + now.duplicates, since.gaps + since.duplicates, "lost or duplicated");
  if (problems.empty()) {
    s.level = io::DiagLevel::Ok;
    s.message = "running";
  } else {
    s.level = io::DiagLevel::Warn;
    for (size_t i = 0; i < problems.size(); ++i) s.message += (i ? "; " : "") + problems[i];
  }
  add_counters(s, now);
  s.values.emplace_back("gaps", std::to_string(now.gaps));
  s.values.emplace_back("duplicates", std::to_string(now.duplicates));
  s.values.emplace_back("verdicts", std::to_string(now.verdicts));
  s.values.emplace_back("violations", std::to_string(now.violations));
  for (const auto& in : now.inputs) {
    s.values.emplace_back("input " + in.name + " received", std::to_string(in.received));
    s.values.emplace_back("input " + in.name + " silent_for", seconds(in.silent_for));
  }
  return s;
}

}  // namespace rvc::runtime
