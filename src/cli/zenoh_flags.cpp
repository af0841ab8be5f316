// Command-line flags of zenoh: endpoints (CLI11). The transport itself knows
// only the plain ZenohOptions struct.
#include <CLI/CLI.hpp>

#include "cli/transport_flags.hpp"

namespace rvc::cli {

void add_zenoh_options(CLI::App& app, transport::ZenohOptions& o) {
  const std::string group = "Zenoh";
  app.add_option("--mode", o.mode, "Zenoh mode: peer, client or router (default peer)")
      ->check(CLI::IsMember({"peer", "client", "router"}))
      ->each([&o](const std::string&) { o.mode_explicit = true; })
      ->group(group);
  app.add_option("--connect", o.connect,
                 "Zenoh endpoint to connect to, e.g. tcp/127.0.0.1:7447 (repeatable, comma list)")
      ->delimiter(',')
      ->group(group);
  app.add_option("--listen", o.listen,
                 "Zenoh endpoint to listen on (repeatable, comma list; default tcp/127.0.0.1:0 "
                 "for peers, tcp/127.0.0.1:7447 for routers)")
      ->delimiter(',')
      ->group(group);
  app.add_flag_callback("--multicast-scouting", [&o] { o.multicast_scouting = 1; },
                        "Discover peers by UDP multicast on the loopback interface (the default without "
                        "--zenoh-config)")
      ->group(group);
  app.add_flag_callback("--no-multicast-scouting", [&o] { o.multicast_scouting = 0; },
                        "No multicast scouting: peers meet only through --connect/--listen endpoints")
      ->group(group);
  app.add_option("--zenoh-config", o.config_file,
                 "Zenoh JSON5 config file; the flags above override it")
      ->check(CLI::ExistingFile)
      ->group(group);
  app.add_flag("--express", o.express, "Publish each sample at once instead of batching")
      ->group(group);
}

}  // namespace rvc::cli
