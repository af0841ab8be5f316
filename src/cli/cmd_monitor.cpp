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
#include "cli/transport_flags.hpp"
#include "cli/signals.hpp"
#include "io/json_writer.hpp"
#include "cli/type_options.hpp"
#include "msg/type_registry.hpp"
#include "runtime/monitor_loop.hpp"
#ifdef RVC_HAVE_MCAP
#include "runtime/check_bag.hpp"
#endif
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
  size_t publishers = 1;  // --publishers: end-of-stream markers to wait for
  double idle_timeout = 0;
  double stats_interval = 0;
  size_t queue_capacity = 1 << 14;
  size_t wait_subscribers = 0;  // per network output, before subscribing to the input
  double wait_timeout = 10;
  TypeOptions typed;                   // --type: payloads are CDR samples of this ROS 2 type
  std::string topic;                   // --topic: of an mcap: input

  // A ROS 2 bag: played through the runtime at once, its topic's type from
  // the bag's own schema (as `rvc check bag.mcap`).
  int run_bag(const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions popts,
              runtime::VerdictOutputs& verdicts) {
#ifdef RVC_HAVE_MCAP
    if (typed.given()) {
      std::fprintf(stderr, "rvc: a bag names the type of each topic itself: drop --type\n");
      return kUsage;
    }
    const runtime::BagInput bag = runtime::select_bag_topic(input.substr(5), topic, typed.registry);
    popts.type = bag.type;
    popts.position_name = "message";
    runtime::Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) { verdicts.put(v); });
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %s, topic %s (%s, %llu messages) -> %zu output%s\n",
                 properties.size(), properties.size() == 1 ? "y" : "ies", input.c_str(), bag.topic.c_str(),
                 bag.type ? bag.type->full_name().c_str() : "JSON", static_cast<unsigned long long>(bag.messages),
                 verdicts.size(), verdicts.size() == 1 ? "" : "s");
    const runtime::Outcome outcome = runtime::check_bag(bag, pipeline, verdicts);
    const auto& s = pipeline.stats();
    const std::string stats = io::JsonObject()
                                  .add("input", input)
                                  .add("topic", bag.topic)
                                  .add("messages", bag.messages)
                                  .add("checked", s.accepted)
                                  .add("rejected", s.rejected)
                                  .add("warnings", s.warnings)
                                  .add("verdicts", verdicts.count())
                                  .add("violations", pipeline.checker().violations())
                                  .str();
    std::fprintf(stderr, "%s\n", stats.c_str());
    return outcome.exit_code();
#else
    (void)properties;
    (void)popts;
    (void)verdicts;
    std::fprintf(stderr, "rvc: this rvc was built without MCAP bags (RVC_WITH_ZENOH=OFF)\n");
    return kUsage;
#endif
  }

  // An output that the input would read back (the same file, an
  // intersecting key expression, the same topic) feeds the monitor its own
  // verdicts without end.
  bool refuse_own_input(const std::string& output) const {
    if (!transport::endpoints_overlap(input, output)) return false;
    std::fprintf(stderr, "rvc: output '%s' would be read back by the input '%s': refusing to monitor its own output\n",
                 output.c_str(), input.c_str());
    return true;
  }

  int run() {
    auto properties = check.properties();
    if (outputs.empty()) outputs.push_back("-");
    for (const auto& uri : outputs)
      if (refuse_own_input(uri)) return kUsage;
    if (!stats_output.empty() && refuse_own_input(stats_output)) return kUsage;
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
        if (!sinks[i]->discovery().empty())
          std::fprintf(stderr, "rvc: this publisher: %s\n", sinks[i]->discovery().c_str());
        return kIncomplete;
      }
    }

    runtime::VerdictOutputs verdicts(std::move(sinks), !check.dense);
    runtime::PipelineOptions popts = check.pipeline_options();
    popts.position_name = "seq";
    if (transport::scheme_of(input) == "mcap") return run_bag(properties, popts, verdicts);
    if (!topic.empty()) {
      std::fprintf(stderr, "rvc: --topic chooses a topic of a bag (--input mcap:PATH)\n");
      return kUsage;
    }
    transport::TransportOptions input_transports = transports;  // outputs stay std_msgs/String
    if (typed.given() && !TypeOptions::typed_scheme(input)) {
      std::fprintf(stderr, "rvc: --type reads typed samples from a dds: topic or CDR payloads from a zenoh: key (as "
                           "zenoh-bridge-ros2dds forwards them); %s inputs carry JSON\n",
                   transport::scheme_of(input).c_str());
      return kUsage;
    }
    popts.type = typed.resolve(input_transports);
    runtime::Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) { verdicts.put(v); });

    runtime::LoopOptions lopts;
    lopts.input = input;
    // A file has nothing more to come after its end.
    const bool from_file = transport::scheme_of(input) == "file";
    lopts.exit_on_eos = exit_on_eos || from_file;
    lopts.publishers = publishers;
    lopts.sequence_numbers = !from_file;
    lopts.idle_timeout = idle_timeout;
    lopts.stats_interval = stats_interval;
    lopts.queue_capacity = queue_capacity;
    lopts.stop_requested = stop_requested;
    lopts.stats_requested = stats_requested;
    runtime::MonitorLoop loop(pipeline, verdicts, stats_sink.get(), lopts);

    auto source = transport::open_source(input, input_transports);
    install_stop_signals();
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %s -> %zu output%s\n", properties.size(),
                 properties.size() == 1 ? "y" : "ies", input.c_str(), verdicts.size(), verdicts.size() == 1 ? "" : "s");
    return loop.run(*source).exit_code();
  }
};

}  // namespace

Runner register_monitor(CLI::App& app) {
  auto cmd = std::make_shared<MonitorCommand>();
  CLI::App* sub = app.add_subcommand("monitor", "Monitor a topic: subscribe, check properties, publish verdicts");
  cmd->check.add_to(*sub);
  sub->add_option("--input,-i", cmd->input, "Endpoint to monitor: zenoh:KEYEXPR, dds:TOPIC, file:PATH, - or mcap:BAG (a ROS 2 bag)")
      ->required();
  sub->add_option("--output,-o", cmd->outputs, "Where verdicts go (repeatable): zenoh:KEY, dds:TOPIC, file:PATH, - (default)")
      ->allow_extra_args(false);
  sub->add_flag("--exit-on-eos", cmd->exit_on_eos,
                "Exit after the publisher's end-of-stream marker (ending any other way is then exit 6)");
  sub->add_option("--publishers", cmd->publishers,
                  "With --exit-on-eos: wait for the end-of-stream markers of at least N publishers (and of every "
                  "publisher seen)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("--idle-timeout", cmd->idle_timeout,
                  "Give up after S seconds without any message (0: wait forever); with --exit-on-eos that is exit 6")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--stats-interval", cmd->stats_interval, "Print counters every S seconds (also on SIGUSR1)");
  sub->add_option("--stats-output", cmd->stats_output, "Also publish the counters (JSON) to this endpoint");
  sub->add_option("--wait-subscribers", cmd->wait_subscribers,
                  "Before reading the input, wait for this many subscribers on each zenoh:/dds: output")
      ->capture_default_str();
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")->capture_default_str();
  cmd->typed.add_to(*sub,
                    "ROS 2 message type of the input's CDR payloads, pkg/msg/Name (`rvc msg list`, `rvc msg show`)");
  sub->add_option("--topic", cmd->topic, "With --input mcap:BAG: the topic to check (if the bag holds several)");
  sub->add_option("--queue", cmd->queue_capacity, "Messages buffered between transport and engine")->capture_default_str();
  add_transport_options(*sub, cmd->transports);
  sub->footer(
      "Exit status: 0 all held, 1 a property was violated, 2 usage/spec error, 3 messages rejected, 4 messages lost,\n"
      "5 runtime failure (an output could not be written), 6 incomplete (nothing received, or no end-of-stream\n"
      "marker with --exit-on-eos).\n"
      "Example: rvc monitor --spec 'historically({emergency} -> once[0:1]{hazard_lights})' \\\n"
      "           --input zenoh:vehicle/status --output zenoh:rv/verdicts");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
