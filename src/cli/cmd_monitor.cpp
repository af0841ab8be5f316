// rvc monitor: a network participant. Subscribes to an endpoint, feeds each
// message to the properties in arrival order on the engine thread, publishes
// verdicts to one or more endpoints, and accounts for every message by its
// publisher sequence number (received, gaps, duplicates, rejected).
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/check_options.hpp"
#include "cli/commands.hpp"
#include "cli/signals.hpp"
#include "io/verdict_writer.hpp"
#include "transport/frame_queue.hpp"
#include "transport/seq_counter.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct MonitorCommand {
  CheckOptions check;
  transport::TransportOptions transports;
  std::string input;
  std::vector<std::string> outputs;
  std::string stats_output;
  bool exit_on_eos = false;
  double stats_interval = 0;
  size_t queue_capacity = 1 << 14;
  size_t wait_subscribers = 0;  // per network output, before subscribing to the input
  double wait_timeout = 10;
  double first_at = 0;  // wall clock when the first message arrived

  // Wall-clock seconds (shared by processes on one host): benchmarks compute
  // "first publish to last verdict" from replay's started_at and our done_at.
  static double wall_now() {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  }

  std::string stats_json(const transport::SeqCounters& c, const Pipeline& p, uint64_t verdicts, bool eos) const {
    char buf[640];
    std::snprintf(buf, sizeof buf,
                  "{\"input\":\"%s\",\"received\":%llu,\"checked\":%llu,\"rejected\":%llu,\"gaps\":%llu,"
                  "\"duplicates\":%llu,\"last_seq\":%llu,\"verdicts\":%llu,\"violations\":%llu,\"eos\":%s,"
                  "\"first_at\":%.6f,\"done_at\":%.6f}",
                  input.c_str(), static_cast<unsigned long long>(c.received),
                  static_cast<unsigned long long>(p.stats().accepted), static_cast<unsigned long long>(p.stats().rejected),
                  static_cast<unsigned long long>(c.gaps), static_cast<unsigned long long>(c.duplicates),
                  static_cast<unsigned long long>(c.last_seq), static_cast<unsigned long long>(verdicts),
                  static_cast<unsigned long long>(p.checker().violations()), eos ? "true" : "false", first_at,
                  wall_now());
    return buf;
  }

  int run() {
    auto properties = check.properties();
    if (outputs.empty()) outputs.push_back("-");
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    for (const auto& uri : outputs) sinks.push_back(transport::open_sink(uri, transports));
    std::unique_ptr<transport::Sink> stats_sink;
    if (!stats_output.empty()) stats_sink = transport::open_sink(stats_output, transports);
    // Verdicts written before a subscriber has matched are lost (volatile
    // QoS), and the first verdict follows the first input message at once:
    // wait for the verdict subscribers before subscribing to the input.
    for (size_t i = 0; i < sinks.size() && wait_subscribers > 0; ++i) {
      if (transport::scheme_of(outputs[i]) == "file") continue;
      std::fprintf(stderr, "rvc monitor: waiting for %zu subscriber%s on %s ...\n", wait_subscribers,
                   wait_subscribers == 1 ? "" : "s", outputs[i].c_str());
      if (!sinks[i]->wait_matched(wait_subscribers, std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)))) {
        std::fprintf(stderr, "rvc: no subscriber matched on %s within %.1f s (--wait-timeout)\n", outputs[i].c_str(),
                     wait_timeout);
        return kUsage;
      }
    }

    uint64_t verdicts = 0;
    std::string line;
    const bool discrete = !check.dense;
    PipelineOptions popts = check.pipeline_options();
    popts.position_name = "seq";
    Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) {
      line.clear();
      io::append_verdict(line, v.time, discrete, v.property, v.value);
      line.pop_back();  // one message per verdict, no newline
      ++verdicts;
      for (auto& s : sinks) s->put(line, verdicts);
    });

    transport::FrameQueue queue(queue_capacity);
    auto source = transport::open_source(input, transports);
    install_stop_signals();
    source->start([&](const transport::Frame& f) { queue.push(f); });
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %s -> %zu output%s\n", properties.size(),
                 properties.size() == 1 ? "y" : "ies", input.c_str(), sinks.size(), sinks.size() == 1 ? "" : "s");

    transport::SeqCounters counters;
    std::vector<transport::OwnedFrame> batch;
    size_t count = 0;
    bool eos = false;
    auto last_stats = std::chrono::steady_clock::now();
    auto publish_stats = [&]() {
      std::string js = stats_json(counters, pipeline, verdicts, eos);
      std::fprintf(stderr, "%s\n", js.c_str());
      if (stats_sink) stats_sink->put(js, 0);
    };
    while (!stop_requested() && !(eos && exit_on_eos)) {
      if (!queue.pop_batch(batch, count, 100)) break;
      if (count == 0) {
        for (auto& s : sinks) s->idle();
        continue;
      }
      if (count > 0 && first_at == 0) first_at = wall_now();
      for (size_t i = 0; i < count; ++i) {
        const transport::OwnedFrame& f = batch[i];
        if (f.eos) {
          counters.on_eos(f.seq);
          eos = true;
          continue;
        }
        counters.on_seq(f.seq);
        pipeline.feed(f.payload, f.seq ? f.seq : counters.received);
      }
      if (stats_requested()) publish_stats();
      if (stats_interval > 0 &&
          std::chrono::steady_clock::now() - last_stats > std::chrono::duration<double>(stats_interval)) {
        last_stats = std::chrono::steady_clock::now();
        publish_stats();
      }
    }
    for (auto& s : sinks) {
      s->put_eos(verdicts);
      s->flush();
    }
    counters.rejected = pipeline.stats().rejected;
    std::string final_stats = stats_json(counters, pipeline, verdicts, eos);  // done_at: last verdict out
    // Close the queue before stopping the source: stop() waits for a running
    // transport callback, which may be blocked on a full queue.
    queue.close();
    source->stop();
    pipeline.finish_report();
    std::fprintf(stderr, "%s\n", final_stats.c_str());
    if (stats_sink) {
      stats_sink->put(final_stats, 0);
      stats_sink->flush();
    }
    if (pipeline.violated()) return kViolated;
    if (counters.gaps > 0 || counters.duplicates > 0) return kLost;
    return pipeline.stats().rejected > 0 ? kBadInput : kOk;
  }
};

}  // namespace

Runner register_monitor(CLI::App& app) {
  auto cmd = std::make_shared<MonitorCommand>();
  CLI::App* sub = app.add_subcommand("monitor", "Monitor a topic: subscribe, check properties, publish verdicts");
  cmd->check.add_to(*sub);
  sub->add_option("--input,-i", cmd->input, "Endpoint to monitor: zenoh:KEYEXPR, dds:TOPIC, file:PATH or -")
      ->required();
  sub->add_option("--output,-o", cmd->outputs, "Where verdicts go (repeatable): zenoh:KEY, dds:TOPIC, file:PATH, - (default)")
      ->allow_extra_args(false);
  sub->add_flag("--exit-on-eos", cmd->exit_on_eos, "Exit after the publisher's end-of-stream marker");
  sub->add_option("--stats-interval", cmd->stats_interval, "Print counters every S seconds (also on SIGUSR1)");
  sub->add_option("--stats-output", cmd->stats_output, "Also publish the counters (JSON) to this endpoint");
  sub->add_option("--wait-subscribers", cmd->wait_subscribers,
                  "Before reading the input, wait for this many subscribers on each zenoh:/dds: output")
      ->capture_default_str();
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")->capture_default_str();
  sub->add_option("--queue", cmd->queue_capacity, "Messages buffered between transport and engine")->capture_default_str();
  transport::add_transport_options(*sub, cmd->transports);
  sub->footer(
      "Exit status: 0 all held, 1 a property was violated, 2 usage/spec error, 3 messages rejected, 4 messages lost.\n"
      "Example: rvc monitor --spec 'historically({emergency} -> once[0:1]{hazard_lights})' \\\n"
      "           --input zenoh:vehicle/status --output zenoh:rv/verdicts");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
