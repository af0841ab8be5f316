// rvc bridge FROM TO [FROM TO]...: forwards every message of one endpoint to
// another, payload and sequence number unchanged, end-of-stream markers
// included. The DDS -> Zenoh bridge of the baseline benchmark
// (`rvc bridge dds:/rvc_perf zenoh:rvc_perf`), and its reverse for ping/pong.
//
// Each route is a Source whose handler publishes on a Sink, on the source's
// transport thread: a reliable sink that blocks slows the source down, and
// with reliable DDS/Zenoh that reaches the original publisher (no queue, no
// loss, no copy beyond what the transports do).
#include <atomic>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/type_options.hpp"
#include "msg/type_registry.hpp"
#include "cli/transport_flags.hpp"
#include "io/json_writer.hpp"
#include "cli/signals.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct Route {
  std::string from, to;
  std::unique_ptr<transport::Sink> sink;
  std::unique_ptr<transport::Source> source;
  transport::TransportOptions transports;  // the bridge's, with this route's type
  std::atomic<uint64_t> forwarded{0};
  std::atomic<uint64_t> eos_count{0};
};

struct BridgeCommand {
  transport::TransportOptions transports;
  std::vector<std::string> uris;
  size_t wait_subscribers = 1;
  double wait_timeout = 30;
  bool exit_on_eos = false;
  double stats_interval = 0;
  TypeOptions typed;  // --type: dds: endpoints are topics of this ROS 2 type; zenoh: ones carry its CDR

  int run() {
    if (uris.size() < 2 || uris.size() % 2 != 0) {
      std::fprintf(stderr, "rvc bridge: give endpoints in pairs: FROM TO [FROM TO]...\n");
      return kUsage;
    }
    // One --type for every route, or one per route in the routes' order (a
    // typed allow-list: the nine Autoware topics, each with its own type).
    const std::vector<std::string> types = typed.type_option ? typed.type_option->results() : std::vector<std::string>{};
    const size_t n_routes = uris.size() / 2;
    if (types.size() > 1 && types.size() != n_routes) {
      std::fprintf(stderr, "rvc bridge: %zu --type for %zu routes: give one for all routes or one per route\n",
                   types.size(), n_routes);
      return kUsage;
    }
    typed.resolve(transports);
    std::vector<std::unique_ptr<Route>> routes;
    for (size_t i = 0; i < uris.size(); i += 2) {
      // A route whose output reaches its own input (or another route's
      // input) forwards its own messages without end.
      for (size_t j = 0; j < uris.size(); j += 2)
        if (transport::endpoints_overlap(uris[j], uris[i + 1])) {
          std::fprintf(stderr, "rvc bridge: route %s -> %s would feed %s\n", uris[i].c_str(), uris[i + 1].c_str(),
                       j == i ? "itself" : ("the route from " + uris[j]).c_str());
          return kUsage;
        }
      auto r = std::make_unique<Route>();
      r->from = uris[i];
      r->to = uris[i + 1];
      r->transports = transports;
#ifdef RVC_HAVE_DDS
      if (types.size() > 1) r->transports.dds.ros_type = &typed.registry.resolve(types[i / 2]);
#endif
      routes.push_back(std::move(r));
    }
    install_stop_signals();
    // Sinks first, and wait for their subscribers: a source that starts
    // forwarding before the far side listens would lose the first messages.
    for (auto& r : routes) {
      r->sink = transport::open_sink(r->to, r->transports);
      if (wait_subscribers > 0) {
        std::fprintf(stderr, "rvc bridge: waiting for %zu subscriber%s on %s ...\n", wait_subscribers,
                     wait_subscribers == 1 ? "" : "s", r->to.c_str());
        if (!r->sink->wait_matched(wait_subscribers,
                                   std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)))) {
          std::fprintf(stderr, "rvc bridge: no subscriber matched on %s within %.1f s (--wait-timeout)\n",
                       r->to.c_str(), wait_timeout);
          if (!r->sink->discovery().empty())
            std::fprintf(stderr, "rvc: this publisher: %s\n", r->sink->discovery().c_str());
          return kIncomplete;
        }
      }
    }
    for (auto& r : routes) {
      // dds: -> anything but dds: forwards on CycloneDDS's receive thread; a
      // dds: sink may wait for acknowledgements that only that thread receives.
      transport::TransportOptions from_opts = r->transports;
#ifdef RVC_HAVE_DDS
      from_opts.dds.deliver_on_receive_thread = transport::scheme_of(r->to) != "dds";
#endif
      r->source = transport::open_source(r->from, from_opts);
      Route* route = r.get();
      r->source->start([route](const transport::Frame& f) {
        if (f.eos) {
          route->sink->put_eos(f.seq);
          route->eos_count.fetch_add(1);
          return;
        }
        route->sink->put(f.payload, f.seq);
        route->forwarded.fetch_add(1, std::memory_order_relaxed);
      });
      std::fprintf(stderr, "rvc bridge: forwarding %s -> %s\n", r->from.c_str(), r->to.c_str());
    }
    std::fflush(stderr);
    auto last = std::chrono::steady_clock::now();
    while (!stop_requested()) {
      if (exit_on_eos) {
        bool all = true;
        for (auto& r : routes) all = all && r->eos_count.load() > 0;
        if (all) break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      if (stats_interval > 0 &&
          std::chrono::steady_clock::now() - last > std::chrono::duration<double>(stats_interval)) {
        last = std::chrono::steady_clock::now();
        for (auto& r : routes)
          std::fprintf(stderr, "rvc bridge: %s -> %s forwarded %llu\n", r->from.c_str(), r->to.c_str(),
                       static_cast<unsigned long long>(r->forwarded.load()));
      }
    }
    for (auto& r : routes) r->source->stop();
    for (auto& r : routes) r->sink->flush();
    io::JsonArray summary;
    for (const auto& r : routes)
      summary.add(io::JsonObject()
                      .add("from", r->from)
                      .add("to", r->to)
                      .add("forwarded", r->forwarded.load())
                      .add("eos", r->eos_count.load()));
    std::string js = io::JsonObject().add_raw("routes", summary.str()).str();
    std::printf("%s\n", js.c_str());
    return kOk;
  }
};

}  // namespace

Runner register_bridge(CLI::App& app) {
  auto cmd = std::make_shared<BridgeCommand>();
  CLI::App* sub = app.add_subcommand(
      "bridge", "Forward messages between endpoints (e.g. dds:TOPIC -> zenoh:KEY), payload and seq unchanged");
  sub->add_option("routes", cmd->uris, "FROM TO pairs: dds:TOPIC, zenoh:KEYEXPR, file:PATH")->required();
  sub->add_option("--wait-subscribers", cmd->wait_subscribers,
                  "Before forwarding, wait for this many subscribers on every TO (0 = do not wait)")
      ->check(in_range(0, 100000))
      ->capture_default_str();
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  sub->add_flag("--exit-on-eos", cmd->exit_on_eos, "Exit once every route forwarded an end-of-stream marker");
  sub->add_option("--stats-interval", cmd->stats_interval, "Print forwarded counts every S seconds (stderr)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  cmd->typed.add_to(*sub,
                  "ROS 2 message type of the samples, pkg/msg/Name: dds: endpoints are topics of this type (as ROS 2 "
                  "nodes publish them), zenoh: endpoints carry their CDR (as zenoh-bridge-ros2dds does); "
                  "repeat it once per route to give each route its own type");
  add_transport_options(*sub, cmd->transports);
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
