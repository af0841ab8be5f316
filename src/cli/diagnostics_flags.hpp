// rvc monitor's health flags: the /diagnostics output (--diagnostics URI,
// --level NAME=warn|error, --name, --diagnostics-period, --stale-after,
// --diagnostics-json) and the monitor announcing itself (a Zenoh liveliness
// token rvc/monitors/<name>; --liveliness-lease on its DDS writers).
// docs/diagnostics.md.
#pragma once

#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "runtime/diagnostics_output.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {

struct DiagnosticsFlags {
  std::vector<std::string> uris;    // --diagnostics (repeatable)
  std::string name = "monitor";     // --name: "rvc: <name>/<property>", rvc/monitors/<name>
  std::vector<std::string> levels;  // --level NAME=warn|error (repeatable)
  double period = 1;
  double stale_after = 5;
  double liveliness_lease = 2;  // seconds; 0: the DDS default (infinite)
  bool json = false;            // zenoh: diagnostics as JSON instead of CDR

  void add_to(CLI::App& app);
  // Checks --name and --level against the properties (and the properties
  // file's level: keys), then opens every --diagnostics URI. Returns 0, or
  // the exit status after printing why.
  int open(const std::vector<engine::PropertySpec>& properties, const std::string& properties_file,
           const transport::TransportOptions& transports, std::unique_ptr<runtime::DiagnosticsOutput>& out) const;
  // DDS writers (verdicts, diagnostics) assert liveliness with the lease.
  void apply_lease(transport::TransportOptions& transports) const;
  // The Zenoh liveliness token rvc/monitors/<name>, when any of `uris` is a
  // zenoh: endpoint (no Zenoh session is opened for it otherwise); null if
  // none. Throws as a Zenoh endpoint.
  std::shared_ptr<void> announce(const std::vector<std::string>& uris,
                                 const transport::TransportOptions& transports) const;
  std::string token_key() const { return "rvc/monitors/" + name; }
};

}  // namespace rvc::cli
