#include "cli/hz_report.hpp"

#include <charconv>
#include <cmath>
#include <limits>

#include "io/json_writer.hpp"

namespace rvc::cli {
namespace {

// Shortest round-trip form: a value read back from /diagnostics is the one computed.
std::string number_text(double v) {
  if (!std::isfinite(v)) return v > 0 ? "inf" : "nan";
  char buf[64];
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, p);
}

std::string number_fixed(double v, int decimals = 5) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

void print_hz_table(std::FILE* out, const std::vector<HzRow>& rows, double now, bool final, bool header) {
  if (header)
    std::fprintf(out, "%-28s %10s %9s %9s %9s %6s %9s %9s %9s %9s %s\n", final ? "FINAL topic" : "topic", "rate_hz",
                 "min_s", "max_s", "std_s", "window", "silence_s", "lat_mean", "lat_max", "received", "state");
  for (const HzRow& row : rows) {
    const runtime::RateSummary s = row.stats->summary(now);
    auto col = [](double v, bool have) { return have ? number_fixed(v) : std::string("-"); };
    const bool intervals = s.window >= 2;
    std::fprintf(out, "%-28s %10s %9s %9s %9s %6zu %9s %9s %9s %9llu %s\n", row.uri->c_str(),
                 intervals ? number_fixed(s.rate, 3).c_str() : "-", col(s.interval_min, intervals).c_str(),
                 col(s.interval_max, intervals).c_str(), col(s.interval_std, intervals).c_str(), s.window,
                 col(s.silence, row.stats->any()).c_str(), col(s.latency_mean, s.latency_samples > 0).c_str(),
                 col(s.latency_max, s.latency_samples > 0).c_str(), static_cast<unsigned long long>(row.received()),
                 runtime::to_string(row.stats->state(now)));
  }
  std::fflush(out);
}

void print_hz_json(std::FILE* out, const std::vector<HzRow>& rows, double now, bool final) {
  for (const HzRow& row : rows) {
    const runtime::RateSummary s = row.stats->summary(now);
    const runtime::TopicState state = row.stats->state(now);
    io::JsonObject o;
    o.add("t", now).add("topic", *row.uri).add("state", runtime::to_string(state))
        .add("level", io::to_string(runtime::diag_level(state)))
        .add("received", row.received()).add("checked", s.received).add("rejected", row.rejected)
        .add("window", static_cast<uint64_t>(s.window));
    const bool intervals = s.window >= 2;
    // null where there is nothing to compute from (JsonObject writes inf as null)
    const double none = std::numeric_limits<double>::infinity();
    o.add("rate_hz", intervals ? s.rate : none)
        .add("interval_mean_s", intervals ? s.interval_mean : none)
        .add("interval_std_s", intervals ? s.interval_std : none)
        .add("interval_min_s", intervals ? s.interval_min : none)
        .add("interval_max_s", intervals ? s.interval_max : none)
        .add("silence_s", row.stats->any() ? s.silence : none)
        .add("latency_samples", static_cast<uint64_t>(s.latency_samples))
        .add("latency_mean_s", s.latency_samples ? s.latency_mean : none)
        .add("latency_max_s", s.latency_samples ? s.latency_max : none)
        .add("final", final);
    std::fprintf(out, "%s\n", o.str().c_str());
  }
  std::fflush(out);
}

io::DiagStatus hz_status(const HzRow& row, double now) {
  const runtime::RateSummary s = row.stats->summary(now);
  const runtime::TopicState state = row.stats->state(now);
  const auto& th = row.stats->thresholds();
  io::DiagStatus d;
  d.level = runtime::diag_level(state);
  d.name = "rvc hz: " + *row.uri;
  d.hardware_id = "rvc";
  d.message = runtime::to_string(state);
  if (state == runtime::TopicState::Timeout) d.message += ": no message for " + number_fixed(s.silence, 3) + " s";
  if (state == runtime::TopicState::WarnRate || state == runtime::TopicState::ErrorRate)
    d.message += ": " + number_fixed(s.rate, 3) + " Hz";
  auto add = [&](const char* key, std::string value) { d.values.emplace_back(key, std::move(value)); };
  const bool intervals = s.window >= 2;
  add("topic", *row.uri);
  add("status", runtime::to_string(state));
  add("rate_hz", intervals ? number_text(s.rate) : "");
  add("warn_rate", number_text(th.warn_rate));
  add("error_rate", number_text(th.error_rate));
  add("timeout", number_text(th.timeout));
  add("window_size", std::to_string(th.window_size));
  add("window", std::to_string(s.window));
  add("interval_min_s", intervals ? number_text(s.interval_min) : "");
  add("interval_max_s", intervals ? number_text(s.interval_max) : "");
  add("interval_std_s", intervals ? number_text(s.interval_std) : "");
  add("silence_s", row.stats->any() ? number_text(s.silence) : "");
  add("latency_mean_s", s.latency_samples ? number_text(s.latency_mean) : "");
  add("latency_max_s", s.latency_samples ? number_text(s.latency_max) : "");
  add("received", std::to_string(row.received()));
  add("rejected", std::to_string(row.rejected));
  return d;
}

}  // namespace rvc::cli
