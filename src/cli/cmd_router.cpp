// rvc router: a Zenoh router in this process, built from the same crate as
// rvc's Zenoh transport, so containers and tests need nothing else installed.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <thread>

#include "cli/commands.hpp"
#include "cli/transport_flags.hpp"
#include "cli/signals.hpp"
#include "transport/zenoh/zenoh_endpoint.hpp"

namespace rvc::cli {

Runner register_router(CLI::App& app) {
  auto opts = std::make_shared<transport::ZenohOptions>();
  CLI::App* sub = app.add_subcommand("router", "Run a Zenoh router (default: listen on tcp/127.0.0.1:7447)");
  add_zenoh_options(*sub, *opts);
  return [opts] {
    opts->mode = "router";
    install_stop_signals();
    std::atomic<bool> stop{false};
    std::thread watcher([&] {
      while (!stop_requested() && !stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
      stop = true;
    });
    int rc = transport::run_zenoh_router(*opts, stop);
    stop = true;
    watcher.join();
    return rc;
  };
}

}  // namespace rvc::cli
