#include "runtime/enforcer.hpp"

#include <stdexcept>

#include "io/cdr_codec.hpp"

namespace rvc::runtime {

EnforceAction parse_enforce_action(const std::string& text) {
  const std::string usage = "--on-violation '" + text + "': expected PROPERTY=URI:PAYLOAD, e.g. p1=zenoh:vehicle/hazard:{\"on\":true}";
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) throw std::invalid_argument(usage);
  EnforceAction a;
  a.property = text.substr(0, eq);
  const std::string rest = text.substr(eq + 1);
  const size_t scheme_end = rest.find(':');
  if (scheme_end == std::string::npos) throw std::invalid_argument(usage);
  const std::string scheme = rest.substr(0, scheme_end);
  if (scheme != "zenoh" && scheme != "dds" && scheme != "file")
    throw std::invalid_argument("--on-violation '" + text + "': commands go to zenoh:KEY, dds:TOPIC or file:PATH, not '" +
                                scheme + ":'");
  const size_t name_end = rest.find(':', scheme_end + 1);
  if (name_end == std::string::npos) throw std::invalid_argument(usage + " (no ':' before the payload)");
  a.uri = rest.substr(0, name_end);
  if (name_end == scheme_end + 1) throw std::invalid_argument(usage + " (no key or topic after '" + scheme + ":')");
  a.payload = rest.substr(name_end + 1);
  return a;
}

namespace {
bool typed_endpoint(const std::string& uri) { return uri.rfind("zenoh:", 0) == 0 || uri.rfind("dds:", 0) == 0; }
}  // namespace

Enforcer::Enforcer(std::vector<EnforceAction> actions, const transport::TransportOptions& transports, double debounce,
                   const msg::MessageType* command_type)
    : debounce_(debounce) {
  for (auto& spec : actions) {
    Action a;
    a.sample = spec.payload;
    if (command_type && typed_endpoint(spec.uri)) {
      std::string error;
      if (!io::json_to_cdr(*command_type, spec.payload, a.sample, error))
        throw std::invalid_argument("--on-violation " + spec.property + ": payload as " + command_type->full_name() +
                                    ": " + error);
      a.eos = spec.uri.rfind("zenoh:", 0) != 0;
    }
    a.spec = std::move(spec);
    a.sink = transport::open_sink(a.spec.uri, transports);
    actions_.push_back(std::move(a));
  }
}

Enforcer::~Enforcer() = default;

void Enforcer::on_verdict(const engine::Verdict& v) {
  auto [it, first] = last_value_.try_emplace(v.property, v.value);
  const bool onset = !v.value && (first || it->second);
  it->second = v.value;
  if (!onset) return;
  const auto now = std::chrono::steady_clock::now();
  for (Action& a : actions_) {
    if (a.spec.property != v.property) continue;
    if (a.fired && now - a.last < std::chrono::duration<double>(debounce_)) {
      ++debounced_;
      continue;
    }
    a.fired = true;
    a.last = now;
    ++commands_;
    a.sink->put(a.sample, ++a.sent);
    a.sink->idle();  // a command is not batched behind later ones
  }
}

bool Enforcer::wait_subscribers(size_t count, std::chrono::milliseconds timeout, std::string& which) {
  for (Action& a : actions_) {
    if (!typed_endpoint(a.spec.uri)) continue;
    if (!a.sink->wait_matched(count, timeout)) {
      which = a.spec.uri;
      return false;
    }
  }
  return true;
}

void Enforcer::finish() {
  for (Action& a : actions_) {
    if (a.eos) a.sink->put_eos(a.sent);
    a.sink->flush();
  }
}

}  // namespace rvc::runtime
