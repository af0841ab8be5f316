#include "runtime/diagnostics_output.hpp"

#include "spec/exact_time.hpp"

#include <cstdio>

#include "io/diagnostics.hpp"

namespace rvc::runtime {
namespace {

double wall_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

}  // namespace

DiagnosticsOutput::DiagnosticsOutput(std::vector<Output> outputs, const std::vector<engine::PropertySpec>& properties,
                                     DiagnosticsOptions options)
    : outputs_(std::move(outputs)), options_(std::move(options)) {
  for (const auto& p : properties) {
    PropertyState state;
    state.name = p.name;
    state.spec = p.spec;
    if (auto it = options_.levels.find(p.name); it != options_.levels.end()) state.on_violation = it->second;
    index_[p.name] = properties_.size();
    properties_.push_back(std::move(state));
  }
}

std::vector<io::DiagStatus> DiagnosticsOutput::statuses(const LoopHealth& health) const {
  std::vector<io::DiagStatus> out;
  out.push_back(monitor_status(options_.identity, health, since_, options_.stale_after));
  for (const auto& p : properties_) out.push_back(property_status(options_.identity, p, health, options_.stale_after));
  return out;
}

std::vector<io::DiagLevel> DiagnosticsOutput::levels(const LoopHealth& health) const {
  std::vector<io::DiagLevel> out;
  for (const auto& s : statuses(health)) out.push_back(s.level);
  return out;
}

void DiagnosticsOutput::publish(const LoopHealth& health) {
  const std::vector<io::DiagStatus> all = statuses(health);
  last_levels_.clear();
  for (const auto& s : all) last_levels_.push_back(s.level);
  const double stamp = wall_now();
  std::string cdr, json;
  ++published_;  // one sequence number per array on every sink (a Zenoh reader counts gaps by it)
  for (auto& o : outputs_) {
    std::string& payload = o.cdr ? cdr : json;
    if (payload.empty())
      payload = o.cdr ? io::diagnostic_array_cdr(stamp, all) : io::diagnostic_array_json(stamp, all);
    o.sink->put(payload, published_);
  }
}

void DiagnosticsOutput::on_verdict(const engine::Verdict& v) {
  auto it = index_.find(v.property);
  if (it == index_.end()) return;
  PropertyState& p = properties_[it->second];
  // Only a first verdict or a new value can change a level (with --all
  // most verdicts repeat the last one: no statuses are built for them).
  const bool changed = !p.has_verdict || p.value != v.value;
  if (!v.value && changed) ++p.violations;
  p.has_verdict = true;
  p.value = v.value;
  p.verdict_time = v.time;
  p.verdict_time_text = v.exact ? spec::seconds_text(v.time_ns) : std::string();  // exact, as verdict lines print it
  ++p.verdicts;
  // A level change goes out at once (with the counters of the last tick),
  // unless an array went out less than kMinGap ago: then the next tick
  // sends it, so a property that flips on every message costs at most 10
  // arrays a second, not one per message.
  // Before the loop's first tick there are no counters yet: that tick sends the first array.
  if (!changed || health_.inputs.empty()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_any_ >= kMinGap && levels(health_) != last_levels_) {
    publish(health_);
    last_any_ = now;
  }
}

void DiagnosticsOutput::on_tick(const MonitorLoop& loop, std::chrono::steady_clock::time_point now) {
  const bool due = now - last_publish_ >= std::chrono::duration<double>(options_.period);
  if (!due && now - last_check_ < kMinGap) return;  // the loop ticks after every batch: look 10 times a second
  on_health(loop.health(now), now);
}

void DiagnosticsOutput::on_health(LoopHealth health, std::chrono::steady_clock::time_point now) {
  const bool due = now - last_publish_ >= std::chrono::duration<double>(options_.period);
  last_check_ = now;
  health_ = std::move(health);
  if (due || levels(health_) != last_levels_) {
    publish(health_);
    last_any_ = now;
    if (due) {
      last_publish_ = now;
      since_ = health_;
    }
  }
  for (auto& o : outputs_) o.sink->idle();
}

void DiagnosticsOutput::finish(const MonitorLoop& loop) {
  health_ = loop.health(std::chrono::steady_clock::now());
  publish(health_);
  // A reader that does not acknowledge the last array in time (it died with
  // the monitor's peers) is no failure of the monitoring: said, not fatal.
  for (auto& o : outputs_) {
    try {
      o.sink->flush();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: warning: diagnostics: %s\n", e.what());
    }
  }
}

}  // namespace rvc::runtime
