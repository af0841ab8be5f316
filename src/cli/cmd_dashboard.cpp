// rvc dashboard: a live web page over a results database (docs/dashboard.md).
// It only reads: `rvc check/monitor --output sqlite:results.db` write the
// rows, possibly at the same time.
#include <csignal>
#include <cstdio>
#include <memory>
#include <stdexcept>

#include "cli/commands.hpp"
#include "cli/signals.hpp"
#include "cli/option_ranges.hpp"
#include "dashboard/api.hpp"
#include "dashboard/server.hpp"
#include "store/database.hpp"

namespace rvc::cli {
namespace {

struct DashboardCommand {
  std::string db;
  std::string listen = "127.0.0.1:8765";
  double poll = 0.2;
  bool allow_remote = false;
  double silent_after = 10;

  int run() {
    dashboard::set_silent_after(silent_after);
    if (!store::is_database_uri(db)) {
      std::fprintf(stderr, "rvc dashboard: --db '%s' is not a results database (sqlite:PATH or postgresql://...)\n",
                   db.c_str());
      return kUsage;
    }
    dashboard::ServerOptions options;
    options.db_uri = db;
    options.poll_seconds = poll;
    options.allow_remote = allow_remote;
    std::string error;
    if (!dashboard::parse_listen(listen, options.host, options.port, error)) {
      std::fprintf(stderr, "rvc dashboard: %s\n", error.c_str());
      return kUsage;
    }
    // No authentication and no TLS: serving other machines is a choice made
    // explicitly, never the result of a typo in --listen.
    if (!allow_remote && !dashboard::is_loopback_host(options.host)) {
      std::fprintf(stderr,
                   "rvc dashboard: refusing to listen on '%s': not a loopback address. The dashboard has no "
                   "authentication; pass --allow-remote to serve other machines\n",
                   options.host.c_str());
      return kUsage;
    }
    dashboard::DashboardServer server(options);
    int port;
    try {
      port = server.start();
    } catch (const store::DbError& e) {
      std::fprintf(stderr, "rvc dashboard: %s\n", e.what());
      return kUsage;
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "rvc dashboard: %s\n", e.what());
      return kRuntime;
    }
    install_stop_signals();
    std::signal(SIGPIPE, SIG_IGN);  // a browser that goes away is a failed write, not the end of rvc
    const bool v6 = options.host.find(':') != std::string::npos;
    std::fprintf(stderr, "rvc dashboard: serving %s on http://%s%s%s:%d\n", server.db_description().c_str(),
                 v6 ? "[" : "", options.host.c_str(), v6 ? "]" : "", port);
    std::fflush(stderr);
    server.run([] { return stop_requested(); });
    std::fprintf(stderr, "rvc dashboard: stopped\n");
    return kOk;
  }
};

}  // namespace

Runner register_dashboard(CLI::App& app) {
  auto cmd = std::make_shared<DashboardCommand>();
  CLI::App* sub = app.add_subcommand("dashboard", "Live web page over a results database");
  sub->add_option("--db", cmd->db, "The results database: sqlite:PATH or postgresql://...")->required();
  sub->add_option("--listen", cmd->listen, "HOST:PORT to serve on (port 0: any free port, printed at start)")
      ->capture_default_str();
  sub->add_option("--poll", cmd->poll, "Seconds between looks for new rows (live updates)")
      ->capture_default_str()
      ->check(in_range(0.05, 10, "seconds"));
  sub->add_option("--silent-after", cmd->silent_after,
                  "A run with no end recorded and no counters recorded for S seconds is shown as silent (its "
                  "monitor died or hangs; a live one records them every second)")
      ->capture_default_str()
      ->check(in_range(0.5, kMaxSeconds, "seconds"));
  sub->add_flag("--allow-remote", cmd->allow_remote,
                "Allow a non-loopback --listen address (the dashboard has no authentication)");
  sub->footer(
      "Example: rvc check --properties props.yaml --output sqlite:results.db trace.jsonl\n"
      "         rvc dashboard --db sqlite:results.db     # then open http://127.0.0.1:8765\n"
      "Exit status: 0 stopped by SIGINT/SIGTERM, 2 bad arguments or a database that cannot be opened,\n"
      "5 the address cannot be bound.");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
