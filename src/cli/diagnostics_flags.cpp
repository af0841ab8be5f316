#include "cli/diagnostics_flags.hpp"

#include <unistd.h>

#include <cctype>
#include <cstdio>
#include <stdexcept>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "io/diagnostics.hpp"
#include "io/properties_file.hpp"
#ifdef RVC_HAVE_ZENOH
#include "transport/zenoh/zenoh_endpoint.hpp"
#endif

namespace rvc::cli {
namespace {

std::string host_name() {
  char buf[256] = {};
  if (gethostname(buf, sizeof buf - 1) != 0 || buf[0] == 0) return "localhost";
  return buf;
}

// One chunk of a Zenoh key and a readable status name: no '/', '*', '$',
// '#', '?' or spaces.
bool valid_name(const std::string& name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

}  // namespace

void DiagnosticsFlags::add_to(CLI::App& app) {
  app.add_option("--diagnostics", uris,
                 "Publish the monitor's health as ROS 2 diagnostic_msgs/msg/DiagnosticArray (repeatable): "
                 "dds:/diagnostics, zenoh:diagnostics (CDR, as rmw_zenoh), file:PATH or - (JSON lines); "
                 "docs/diagnostics.md");
  app.add_option("--name", name,
                 "The monitor's name: statuses are 'rvc: NAME/<property>' and 'rvc: NAME/monitor', its Zenoh "
                 "liveliness token rvc/monitors/NAME (letters, digits, _ - .)")
      ->capture_default_str();
  app.add_option("--level", levels,
                 "Diagnostics: report PROPERTY's violation as warn or error (default error), PROPERTY=warn "
                 "(repeatable; a properties file may give level: warn)");
  app.add_option("--diagnostics-period", period, "Diagnostics: seconds between two arrays (and on every level change)")
      ->check(in_range(0.01, kMaxSeconds, "seconds"))
      ->capture_default_str();
  app.add_option("--stale-after", stale_after,
                 "Diagnostics: a property is STALE after S seconds without a message on an input (0: never)")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  app.add_flag("--diagnostics-json", json, "Diagnostics on zenoh: as JSON instead of CDR samples");
  app.add_option("--liveliness-lease", liveliness_lease,
                 "DDS writers of verdicts and diagnostics assert liveliness (AUTOMATIC) with this lease in seconds, "
                 "so readers see a dead monitor (0: DDS default, infinite)")
      ->check(in_range(0, 3600, "seconds"))
      ->capture_default_str();
}

int DiagnosticsFlags::open(const std::vector<engine::PropertySpec>& properties, const std::string& properties_file,
                           const transport::TransportOptions& transports,
                           std::unique_ptr<runtime::DiagnosticsOutput>& out) const {
  if (!valid_name(name)) {
    std::fprintf(stderr, "rvc: --name '%s': use letters, digits, '_', '-' or '.' (it names the statuses and the "
                         "liveliness token rvc/monitors/NAME)\n", name.c_str());
    return kUsage;
  }
  if (uris.empty()) {
    if (!levels.empty()) {
      std::fprintf(stderr, "rvc: --level sets a property's /diagnostics level: give --diagnostics URI too\n");
      return kUsage;
    }
    return 0;
  }
  runtime::DiagnosticsOptions options;
  options.identity = {name, host_name()};
  options.period = period;
  options.stale_after = stale_after;
  auto known = [&](const std::string& property) {
    for (const auto& p : properties)
      if (p.name == property) return true;
    return false;
  };
  if (!properties_file.empty())
    for (const auto& l : io::load_property_levels(properties_file))
      options.levels[l.name] = runtime::parse_violation_level(l.level);
  for (const auto& text : levels) {
    const size_t eq = text.find('=');
    const std::string property = eq == std::string::npos ? "" : text.substr(0, eq);
    if (property.empty()) {
      std::fprintf(stderr, "rvc: --level '%s': expected PROPERTY=warn or PROPERTY=error\n", text.c_str());
      return kUsage;
    }
    if (!known(property)) {
      std::string names;
      for (const auto& p : properties) names += (names.empty() ? "" : ", ") + p.name;
      std::fprintf(stderr, "rvc: --level %s: no property of that name (the properties: %s)\n", property.c_str(),
                   names.c_str());
      return kUsage;
    }
    try {
      options.levels[property] = runtime::parse_violation_level(text.substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      std::fprintf(stderr, "rvc: --level %s: %s\n", text.c_str(), e.what());
      return kUsage;
    }
  }
  // DDS: a typed DiagnosticArray topic, reliable keep-last 10 as a ROS 2
  // publisher's default (a write never waits for a slow reader; the last
  // array's flush waits up to 1 s for acknowledgements).
  transport::TransportOptions diag_transports = transports;
#ifdef RVC_HAVE_DDS
  diag_transports.dds.ros_type = &io::diagnostic_array_type();
  diag_transports.dds.qos = "reliable,keep-last=10,max-blocking=1s";
#endif
  apply_lease(diag_transports);
  std::vector<runtime::DiagnosticsOutput::Output> outputs;
  for (const auto& uri : uris) {
    const std::string scheme = transport::scheme_of(uri);
    runtime::DiagnosticsOutput::Output o;
    o.cdr = scheme == "dds" || (scheme == "zenoh" && !json);
    o.sink = transport::open_sink(uri, diag_transports);
    outputs.push_back(std::move(o));
  }
  out = std::make_unique<runtime::DiagnosticsOutput>(std::move(outputs), properties, std::move(options));
  return 0;
}

void DiagnosticsFlags::apply_lease(transport::TransportOptions& transports) const {
#ifdef RVC_HAVE_DDS
  transports.dds.liveliness_lease = std::chrono::milliseconds(static_cast<long>(liveliness_lease * 1000));
#else
  (void)transports;
#endif
}

std::shared_ptr<void> DiagnosticsFlags::announce(const std::vector<std::string>& all_uris,
                                                 const transport::TransportOptions& transports) const {
#ifdef RVC_HAVE_ZENOH
  for (const auto& uri : all_uris)
    if (transport::scheme_of(uri) == "zenoh") return transport::make_zenoh_liveliness_token(token_key(), transports.zenoh);
#else
  (void)all_uris;
  (void)transports;
#endif
  return nullptr;
}

}  // namespace rvc::cli
