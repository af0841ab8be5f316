// rvc sync: the paper's Message Synchronizer as its own participant. Several
// named inputs -> one policy (merge, approximate, exact, latest) -> each set
// published as one JSON object {"time": stamp, "gear": {...}, "steer": {...}}
// on every output, which `rvc monitor` (or `rvc check` on a file) then reads
// as one stream with properties over {gear.report}, {steer.…}.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "cli/option_ranges.hpp"
#include "cli/option_rules.hpp"
#include "cli/output_sinks.hpp"
#include "cli/signals.hpp"
#include "cli/sync_options.hpp"
#include "cli/transport_flags.hpp"
#include "cli/type_options.hpp"
#include "runtime/monitor_loop.hpp"
#include "runtime/synced_pipeline.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct SyncCommand {
  std::vector<std::string> inputs;
  CLI::Option* input_option = nullptr;
  CLI::App* app = nullptr;
  std::vector<std::string> outputs;
  std::string stats_output;
  SyncFlags sync;
  TypeOptions typed;
  transport::TransportOptions transports;
  std::string time_field = "time";
  size_t max_message_size = 1 << 20;
  CLI::Option* max_message_size_option = nullptr;
  bool exit_on_eos = false;
  size_t publishers = 1;
  double idle_timeout = 0;
  double stats_interval = 0;
  size_t wait_subscribers = 0;
  double wait_timeout = 10;
  std::string set_type;      // --set-type: publish sets typed, as this message of the inputs' types
  std::string set_type_dir;  // --set-type-dir: where its .msg definition is written for subscribers

  // The set as a ROS 2 message: float64 time, then each input's message
  // under its name. Registered (and written to --set-type-dir) so the sets
  // can be published typed; every input must be typed.
  const msg::MessageType* define_set_type(const std::vector<runtime::SyncInput>& named) {
    std::string text = "# Written by rvc sync: one synchronized set (time = the set's stamp, seconds).\nfloat64 time\n";
    for (const auto& in : named) {
      if (!in.type)
        throw std::invalid_argument("--set-type: input '" + in.name + "' carries JSON; typed sets need every input typed");
      text += in.type->package + "/" + in.type->name + " " + in.name + "\n";
    }
    typed.registry.add_definition(set_type, text, "rvc sync --set-type");
    const msg::MessageType* t = &typed.registry.resolve(set_type);
    if (!set_type_dir.empty()) {
      const std::filesystem::path dir = std::filesystem::path(set_type_dir) / t->package / "msg";
      std::filesystem::create_directories(dir);
      // Only a new file, or one an earlier rvc sync wrote (its first line), is
      // written: a definition of the same name that rvc did not write is left as it is.
      const std::filesystem::path file = dir / (t->name + ".msg");
      if (std::filesystem::exists(file)) {
        std::ifstream in(file);
        std::string first;
        std::getline(in, first);
        if (first + "\n" != text.substr(0, text.find('\n') + 1))
          throw std::invalid_argument("--set-type-dir: '" + file.string() +
                                      "' exists and was not written by rvc sync: refusing to overwrite it");
      }
      std::ofstream out(file, std::ios::trunc);
      out << text;
      if (!out.flush()) throw std::runtime_error("--set-type-dir: cannot write '" + file.string() + "'");
    }
    std::fprintf(stderr, "rvc sync: sets are %s:\n%s", t->full_name().c_str(), text.c_str());
    return t;
  }

  int run() {
    if (outputs.empty()) outputs.push_back("-");
    std::vector<transport::TransportOptions> per_input;
    auto named = sync.resolve(inputs, *app, input_option, typed, transports, per_input);
    std::vector<std::string> names;
    size_t files = 0;
    for (const auto& in : named) {
      names.push_back(in.name);
      files += transport::scheme_of(in.uri) == "file";
      for (const auto& out : outputs)
        if (transport::reads_back(in.uri, out)) {
          std::fprintf(stderr, "rvc: output '%s' would be read back by the input '%s'\n", out.c_str(), in.uri.c_str());
          return kUsage;
        }
    }
    if (files != 0 && files != named.size()) {
      std::fprintf(stderr, "rvc: inputs are all files or all topics, not a mix\n");
      return kUsage;
    }
    const msg::MessageType* typed_sets = set_type.empty() ? nullptr : define_set_type(named);
    transport::TransportOptions out_transports = transports;
#ifdef RVC_HAVE_DDS
    out_transports.dds.ros_type = typed_sets;
#endif
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    if (int status = open_outputs(outputs, out_transports, wait_subscribers, wait_timeout, "sync", sinks))
      return status;
    std::unique_ptr<transport::Sink> stats_sink;
    if (!stats_output.empty()) stats_sink = transport::open_sink(stats_output, transports);
    runtime::VerdictOutputs sets(std::move(sinks), true);
    if (typed_sets) {
      std::vector<bool> typed_sinks;
      for (const auto& uri : outputs)  // rmw_zenoh: outputs stay std_msgs/String JSON
        typed_sinks.push_back(TypeOptions::typed_scheme(uri) && transport::scheme_of(uri) != "rmw_zenoh");
      sets.set_typed(typed_sets, typed_sinks);
    }

    runtime::PipelineOptions popts;
    popts.parse_only = true;  // no properties: sets only
    popts.time_field = time_field;
    popts.max_message_size = max_message_size;
    if (max_message_size_option->count()) popts.max_typed_message_size = max_message_size;
    popts.position_name = files ? "line" : "seq";
    runtime::SyncedPipeline pipeline({}, popts, named, sync.options(named), [](const engine::Verdict&) {},
                                     [&](std::string_view json, double) { sets.put_payload(json); });

    runtime::LoopOptions lopts;
    lopts.input = SyncFlags::joined_names(named);
    lopts.input_names = names;
    lopts.exit_on_eos = exit_on_eos || files;
    lopts.publishers = publishers;
    lopts.sequence_numbers = files == 0;
    lopts.idle_timeout = idle_timeout;
    lopts.stats_interval = stats_interval;
    lopts.stop_requested = stop_requested;
    lopts.stats_requested = stats_requested;
    runtime::MonitorLoop loop(pipeline, sets, stats_sink.get(), lopts);
    SyncFlags::Sources sources = SyncFlags::open_sources(named, per_input);
    install_stop_signals();
    std::fprintf(stderr, "rvc sync: %zu inputs (%s), %s -> %zu output%s\n", named.size(), lopts.input.c_str(),
                 sync.policy.c_str(), sets.size(), sets.size() == 1 ? "" : "s");
    const runtime::Outcome outcome = loop.run(sources.list);
    return outcome.exit_code();
  }
};

}  // namespace

Runner register_sync(CLI::App& app) {
  auto cmd = std::make_shared<SyncCommand>();
  CLI::App* sub = app.add_subcommand(
      "sync", "Synchronize several topics into one stream of sets (JSON), the paper's Message Synchronizer");
  cmd->app = sub;
  cmd->input_option = sub->add_option("--input,-i", cmd->inputs,
                                      "NAME=URI (repeatable): zenoh:KEYEXPR, dds:TOPIC or file:PATH; each set holds "
                                      "the input's message under NAME")
                          ->required();
  sub->add_option("--output,-o", cmd->outputs, "Where sets go (repeatable): zenoh:KEY, dds:TOPIC, file:PATH, - (default)")
      ->allow_extra_args(false);
  cmd->typed.add_to(*sub, "ROS 2 type of the --input before it (or NAME=pkg/msg/Name)");
  cmd->sync.add_to(*sub);
  sub->add_option("--set-type", cmd->set_type,
                  "Publish sets on dds:/zenoh: outputs typed, as this message (e.g. rvc_sync/msg/Set): float64 time "
                  "plus each input's message under its name; needs every input typed");
  sub->add_option("--set-type-dir", cmd->set_type_dir,
                  "Write the --set-type definition here (DIR/pkg/msg/Name.msg) for subscribers' --msg-path");
  sub->add_option("--time-field", cmd->time_field, "JSON inputs: the field holding the stamp (seconds)")
      ->check(field_name())
      ->capture_default_str();
  cmd->max_message_size_option =
      sub->add_option("--max-message-size", cmd->max_message_size,
                      "Longest accepted message in bytes (default: 1 MiB for JSON, 256 MiB for typed input)")
          ->check(in_range(1, kMaxMessageSize, "bytes"));
  sub->add_flag("--exit-on-eos", cmd->exit_on_eos, "Exit after every input's end-of-stream marker");
  sub->add_option("--publishers", cmd->publishers, "With --exit-on-eos: publishers per input to wait for")
      ->check(in_range(1, 100000));
  sub->add_option("--idle-timeout", cmd->idle_timeout, "Give up after S seconds without any message (0: never)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--stats-interval", cmd->stats_interval, "Print counters every S seconds (also on SIGUSR1)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--stats-output", cmd->stats_output, "Also publish the counters (JSON) to this endpoint");
  sub->add_option("--wait-subscribers", cmd->wait_subscribers,
                  "Before reading the inputs, wait for this many subscribers on each zenoh:/dds: output")
      ->check(in_range(0, 100000));
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  add_transport_options(*sub, cmd->transports);
  sub->footer(
      "Each set: {\"time\": STAMP, \"NAME\": message, ...}; merge sets hold every input's latest message.\n"
      "Example: rvc sync --input gear=dds:/vehicle/status/gear_status --type autoware_auto_vehicle_msgs/msg/GearReport \\\n"
      "           --input steer=dds:/vehicle/status/steering_status --type autoware_auto_vehicle_msgs/msg/SteeringReport \\\n"
      "           --sync approximate --output dds:/rv/synced");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
