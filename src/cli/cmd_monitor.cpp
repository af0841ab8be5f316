// rvc monitor: a network participant. Subscribes to an endpoint, feeds each
// message to the properties in arrival order on the engine thread, publishes
// verdicts to one or more endpoints, and accounts for every message by its
// publisher sequence number (received, gaps, duplicates, rejected).
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli/instance_options.hpp"
#include "cli/check_options.hpp"
#include "cli/clock_options.hpp"
#include "cli/option_ranges.hpp"
#include "cli/commands.hpp"
#include "cli/diagnostics_flags.hpp"
#include "cli/group_options.hpp"
#include "cli/store_options.hpp"
#include "cli/transport_flags.hpp"
#include "cli/signals.hpp"
#include "io/json_writer.hpp"
#include "cli/output_sinks.hpp"
#include "cli/sync_options.hpp"
#include "cli/type_options.hpp"
#include "msg/service_types.hpp"
#include "msg/type_registry.hpp"
#include "runtime/enforcer.hpp"
#include "runtime/forwarder.hpp"
#include "runtime/message_filter.hpp"
#include "runtime/monitor_loop.hpp"
#include "runtime/service_call_feed.hpp"
#include "runtime/synced_pipeline.hpp"
#include "cli/bag_run.hpp"
#include "transport/rosbag2/bag_reader.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

struct MonitorCommand {
  CheckOptions check;
  ClockFlags clock;  // --clock, --tick: dense time moves on while no message comes
  transport::TransportOptions transports;
  std::vector<std::string> inputs;     // --input: one URI, or several NAME=URI
  CLI::Option* input_option = nullptr;
  CLI::App* app = nullptr;
  SyncFlags sync;
  std::string input;                   // the one input
  std::vector<std::string> outputs;
  std::string stats_output;
  std::string sets_output;             // several inputs: also publish the sets checked
  std::string verdict_type;            // --verdict-type: typed verdicts on dds:/zenoh: outputs
  bool exit_on_eos = false;
  size_t publishers = 1;  // --publishers: end-of-stream markers to wait for
  double idle_timeout = 0;
  double stats_interval = 0;
  size_t queue_capacity = 1 << 14;
  std::string handoff = "auto";        // --handoff: queue | inline | auto (runtime/monitor_loop.hpp)
  size_t wait_subscribers = 0;  // per network output, before subscribing to the input
  double wait_timeout = 10;
  TypeOptions typed;                   // --type: payloads are CDR samples of this ROS 2 type
  std::vector<std::string> topics;     // --topic: of an mcap: input
  StoreFlags store;                    // a results database among the outputs
  std::vector<std::string> on_violation;  // --on-violation PROPERTY=URI:PAYLOAD
  double debounce = 0;
  std::string command_type;            // --command-type: typed commands
  std::unique_ptr<runtime::Enforcer> enforcer;
  runtime::FilterOptions filter_options;  // --allow/--deny/--project
  std::unique_ptr<runtime::MessageFilter> filter;
  std::string forward_property;           // --forward: ROSMonitoring's filter action
  std::string forward_to;
  DiagnosticsFlags health;                 // --diagnostics, --name, --level, liveliness
  std::unique_ptr<runtime::DiagnosticsOutput> diagnostics;
  std::shared_ptr<void> liveliness_token;  // rvc/monitors/<name> while the monitor runs
  GroupFlags group;                        // --group, --shard-by: one replica of a monitor group
  std::unique_ptr<runtime::fleet::ShardedFeed> sharded;
  InstanceFlags instances;  // --instances-by: one monitor instance per key value (docs/semantics.md)
  runtime::InstanceOptions iopts;

  // --group: refuses what a replica cannot do, then joins (token, member set).
  int join_group(const std::vector<std::string>& uris) {
    std::string why = group.refuse(uris);
    if (why.empty() && check.calls) why = "--group checks each shard's messages; --calls is for one service";
    if (why.empty() && !forward_property.empty()) why = "--group: --forward republishes one input, not shards";
    if (why.empty() && clock.clock != "auto" && clock.clock != "off")
      why = "--group: the instances move with their own messages; drop --clock";
    if (!why.empty()) {
      std::fprintf(stderr, "rvc: %s\n", why.c_str());
      return kUsage;
    }
    try {
      group.join(transports);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kRuntime;
    }
    return 0;
  }
  // The feed of a replica: one instance per owned shard, made by `factory`.
  runtime::Feed& make_sharded(runtime::fleet::InstanceFactory factory, runtime::VerdictOutputs& verdicts) {
    auto opts = group.sharded_options();
    if (results) opts.on_handover = [this](const std::string& json) { results->counters(json); };
    sharded = std::make_unique<runtime::fleet::ShardedFeed>(runtime::fleet::ShardPattern(group.shard_by),
                                                             group.members(), std::move(factory), verdicts, opts);
    return *sharded;
  }

  // The /diagnostics output (fed by the verdicts and the loop's ticks) and
  // the Zenoh liveliness token, once the outputs are open.
  int open_health(const std::vector<engine::PropertySpec>& properties, runtime::VerdictOutputs& verdicts,
                  const std::vector<std::string>& input_uris) {
    if (int status = health.open(properties, check.properties_file, transports, diagnostics)) return status;
    if (diagnostics) verdicts.observe([this](const engine::Verdict& v) { diagnostics->on_verdict(v); });
    std::vector<std::string> uris = input_uris;
    uris.insert(uris.end(), outputs.begin(), outputs.end());
    uris.insert(uris.end(), health.uris.begin(), health.uris.end());
    liveliness_token = health.announce(uris, transports);
    if (liveliness_token) std::fprintf(stderr, "rvc monitor: liveliness token %s\n", health.token_key().c_str());
    return 0;
  }
  void attach_health(runtime::LoopOptions& lopts) {
    if (diagnostics)
      lopts.on_tick = [this](const runtime::MonitorLoop& loop, std::chrono::steady_clock::time_point now) {
        diagnostics->on_tick(loop, now);
      };
  }
  // The last array, with the final counters; a failing output fails the run.
  void finish_health(runtime::Outcome& outcome, const runtime::MonitorLoop& loop) {
    liveliness_token.reset();
    // Killed or stopped by a signal, the others take this replica's shards
    // over; at the end of the stream they keep them (it checked everything).
    // --shard-subscribe owned: a replica sees only its shards' end-of-stream
    // markers, so it ends at --idle-timeout once the fleet went quiet, and
    // that too is an orderly end (docs/fleet.md).
    const auto end = loop.end_reason();
    group.leave(end == runtime::EndReason::EndOfStream ||
                (group.subscribe_owned() && end == runtime::EndReason::IdleTimeout));  // an orderly end: the token goes at once (a killed monitor's when its lease expires)
    if (!diagnostics) return;
    try {
      diagnostics->finish(loop);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: error: %s\n", e.what());
      outcome.runtime_failure = true;
    }
  }

  // The filter in front of the monitor, keyed per input by its topic or key.
  void set_filter(runtime::LoopOptions& lopts, const std::vector<std::string>& uris) {
    filter = std::make_unique<runtime::MessageFilter>(filter_options);
    if (!filter->active()) return;
    lopts.filter = filter.get();
    for (const auto& uri : uris) {
      const size_t colon = uri.find(':');
      lopts.key_of_input.push_back(colon == std::string::npos ? uri : uri.substr(colon + 1));
    }
  }

  static int check_property_name(const std::string& name, const std::vector<engine::PropertySpec>& properties,
                                 const char* flag) {
    for (const auto& p : properties)
      if (p.name == name) return 0;
    std::string names;
    for (const auto& p : properties) names += (names.empty() ? "" : ", ") + p.name;
    std::fprintf(stderr, "rvc: %s %s: no property of that name (the properties: %s)\n", flag, name.c_str(),
                 names.c_str());
    return kUsage;
  }

  // The enforcer's endpoints, opened with the outputs (and waited for like them).
  // A command endpoint the monitor reads is refused before anything is
  // opened: a file would be truncated before it is read, a key or topic
  // would feed each command back as a message (without end, once violated).
  int open_enforcer(const std::vector<engine::PropertySpec>& properties, runtime::VerdictOutputs& verdicts,
                    const std::vector<std::string>& input_uris) {
    if (on_violation.empty()) return 0;
    std::vector<runtime::EnforceAction> actions;
    for (const auto& text : on_violation) {
      actions.push_back(runtime::parse_enforce_action(text));
      if (int status = check_property_name(actions.back().property, properties, "--on-violation")) return status;
      for (const auto& in : input_uris)
        if (transport::reads_back(in, actions.back().uri)) {
          std::fprintf(stderr,
                       "rvc: --on-violation %s: '%s' would be read back by the input '%s': refusing to send commands "
                       "to the monitor's own input\n",
                       actions.back().property.c_str(), actions.back().uri.c_str(), in.c_str());
          return kUsage;
        }
    }
    const msg::MessageType* type = nullptr;
    transport::TransportOptions command_transports = transports;
    if (!command_type.empty()) {
      for (const auto& p : typed.msg_paths) typed.registry.add_search_path(p);
      type = &typed.registry.resolve(command_type);
#ifdef RVC_HAVE_DDS
      command_transports.dds.ros_type = type;
#endif
    }
    enforcer = std::make_unique<runtime::Enforcer>(std::move(actions), command_transports, debounce, type);
    std::string which;
    if (wait_subscribers > 0 &&
        !enforcer->wait_subscribers(wait_subscribers, std::chrono::milliseconds(static_cast<long>(wait_timeout * 1000)),
                                    which)) {
      std::fprintf(stderr, "rvc: no subscriber matched on %s within %.1f s (--wait-timeout)\n", which.c_str(),
                   wait_timeout);
      return kIncomplete;
    }
    verdicts.observe([this](const engine::Verdict& v) { enforcer->on_verdict(v); });
    return 0;
  }
  int finish_enforcer(int status) {
    if (!enforcer) return status;
    try {
      enforcer->finish();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: error: %s\n", e.what());
      if (status == kOk) status = kRuntime;
    }
    std::fprintf(stderr, "rvc monitor: %llu command%s sent on violation (%llu debounced)\n",
                 static_cast<unsigned long long>(enforcer->commands()), enforcer->commands() == 1 ? "" : "s",
                 static_cast<unsigned long long>(enforcer->debounced()));
    return status;
  }
  std::unique_ptr<runtime::ResultsOutput> results;

  // Records the run in the results database (if one is given) and hooks it
  // to the pipeline's messages, the verdicts and the loop's counters.
  void attach_results(const std::string& input_name, runtime::PipelineOptions& popts,
                      runtime::VerdictOutputs& verdicts) {
    results = store.open();
    if (results) results->attach(input_name, popts, verdicts);
  }
  // Once the pipeline is built (its specs are valid).
  void start_results(const std::vector<std::string>& input_uris, const std::vector<engine::PropertySpec>& properties) {
    if (results) results->start(runtime::run_info(command_line(), input_uris, properties, check.dense));
  }
  void record_counters(runtime::LoopOptions& lopts) {
    if (results) lopts.on_record = [this](const std::string& json) { results->counters(json); };
  }
  int finish_results(runtime::Outcome outcome, const runtime::MonitorLoop& loop) {
    if (results) results->finish(outcome, runtime::to_string(loop.end_reason()), loop.final_stats());
    return finish_enforcer(outcome.exit_code());
  }

  // A path of a file: input (a plain path, file:PATH), "" for anything else.
  static std::string file_path(const std::string& uri) {
    if (transport::scheme_of(uri) != "file" || uri == "-") return "";
    return uri.rfind("file:", 0) == 0 ? uri.substr(5) : uri;
  }
  // bag:PATH, mcap:PATH, or a file or folder that is a bag by its content.
  static bool is_bag_input(const std::string& uri) {
    if (transport::scheme_of(uri) == "mcap") return true;
    const std::string path = file_path(uri);
    return !path.empty() && transport::is_bag(path);
  }
  // A binary file where JSON lines are expected: one clear line, not an error per line.
  static bool refuse_binary_file(const std::string& uri) {
    const std::string path = file_path(uri);
    if (path.empty()) return false;
    const std::string what = transport::binary_signature(path);
    if (what.empty()) return false;
    std::fprintf(stderr, "rvc: input '%s' is %s, not JSON lines\n", path.c_str(), what.c_str());
    return true;
  }

  // A ROS 2 bag: played through the runtime at once, its topic's type from
  // the bag's own schema (as `rvc check bag.mcap`).
  int run_bag(const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions popts,
              runtime::VerdictOutputs& verdicts) {
    if (typed.given()) {
      std::fprintf(stderr, "rvc: a bag names the type of each topic itself: drop --type\n");
      return kUsage;
    }
    const std::string path =
        transport::scheme_of(input) == "mcap" ? input.substr(input.find(':') + 1) : file_path(input);
    // A bad spec (or a combination refused whatever the input) ends the run before it announces
    // itself or writes a result, as for a file: input.
    runtime::check_specs(properties, check.dense);
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %s -> %zu output%s\n", properties.size(),
                 properties.size() == 1 ? "y" : "ies", input.c_str(), verdicts.size(), verdicts.size() == 1 ? "" : "s");
    attach_results(input, popts, verdicts);
    start_results({input}, properties);
    for (const auto& dir : typed.msg_paths) typed.registry.add_search_path(dir);  // what the schemas leave out
    if (check.calls && topics.size() > 1) {
      std::fprintf(stderr, "rvc: --calls pairs the events of one service topic (--topic /svc/_service_event)\n");
      return kUsage;
    }
    BagRun run = cli::run_bag(path, topics, properties, popts, sync, typed.registry, verdicts,
                              clock.ticks_at_end(check.dense || check.calls), check.calls_timeout());
    std::fprintf(stderr, "rvc monitor: %s\n", run.description.c_str());
    const std::string stats = run.counters_json(input, verdicts.count());
    std::fprintf(stderr, "%s\n", stats.c_str());
    if (results) results->finish(run.outcome, run.stopped ? "signal" : "end of bag", stats);
    return finish_enforcer(run.outcome.exit_code());
  }

  // Everything this run writes, by the option that names it.
  std::vector<std::pair<std::string, std::string>> written_targets() const {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto& uri : outputs) out.emplace_back("--output", uri);
    if (!stats_output.empty()) out.emplace_back("--stats-output", stats_output);
    for (const auto& uri : health.uris) out.emplace_back("--diagnostics", uri);
    if (!store.database.empty()) out.emplace_back("the results database", store.database);
    if (!store.options.spool.empty()) out.emplace_back("--spool", store.options.spool);
    return out;
  }

  // An output that the input would read back (the same file, an
  // intersecting key expression, the same topic) feeds the monitor its own
  // verdicts without end.
  bool refuse_own_input(const std::string& output, const std::string& in) const {
    if (!transport::reads_back(in, output)) return false;
    std::fprintf(stderr, "rvc: output '%s' would be read back by the input '%s': refusing to monitor its own output\n",
                 output.c_str(), in.c_str());
    return true;
  }
  bool refuse_own_inputs(const std::vector<std::string>& uris) const {
    for (const auto& in : uris) {
      for (const auto& uri : outputs)
        if (refuse_own_input(uri, in)) return true;
      if (!stats_output.empty() && refuse_own_input(stats_output, in)) return true;
      for (const auto& uri : health.uris)
        if (refuse_own_input(uri, in)) return true;
    }
    return false;
  }

  int open_outputs(std::vector<std::unique_ptr<transport::Sink>>& sinks, std::unique_ptr<transport::Sink>& stats_sink) {
    transport::TransportOptions verdict_transports = transports;
#ifdef RVC_HAVE_DDS
    verdict_transports.dds.ros_type = verdict_msg_type();
#endif
    health.apply_lease(verdict_transports);
    if (int status = cli::open_outputs(outputs, verdict_transports, wait_subscribers, wait_timeout, "monitor", sinks))
      return status;
    if (!stats_output.empty()) stats_sink = transport::open_sink(stats_output, transports);
    return 0;
  }

  // The verdicts' ROS 2 type (null: std_msgs/String JSON); resolved once.
  const msg::MessageType* verdict_msg_type() {
    if (verdict_type.empty()) return nullptr;
    if (!verdict_msg_) {
      for (const auto& p : typed.msg_paths) typed.registry.add_search_path(p);
      verdict_msg_ = &typed.registry.resolve(verdict_type);
    }
    return verdict_msg_;
  }
  const msg::MessageType* verdict_msg_ = nullptr;

  runtime::VerdictOutputs make_verdicts(std::vector<std::unique_ptr<transport::Sink>> sinks) {
    runtime::VerdictOutputs verdicts(std::move(sinks), !check.dense);
    // mcap: outputs place verdicts of live inputs at the wall-clock time they were made (the
    // timeline of a `ros2 bag record` made alongside); a bag's at its messages' log times.
    for (const auto& in : inputs) {
      const size_t eq = in.find('='), colon = in.find(':');
      const std::string scheme =
          transport::scheme_of(eq != std::string::npos && (colon == std::string::npos || eq < colon) ? in.substr(eq + 1) : in);
      if (scheme == "zenoh" || scheme == "dds" || scheme == "rmw_zenoh") verdicts.use_wall_clock(true);
    }
    if (verdict_msg_type()) {
      std::vector<bool> typed_sinks;
      // rmw_zenoh: outputs stay std_msgs/String JSON (a typed key needs the type's REP-2016 hash).
      for (const auto& uri : outputs)
        typed_sinks.push_back(TypeOptions::typed_scheme(uri) && transport::scheme_of(uri) != "rmw_zenoh");
      verdicts.set_typed(verdict_msg_type(), typed_sinks);
    }
    return verdicts;
  }

  // Several named inputs: synchronized into one stream in this process.
  int run_synced() {
    auto properties = check.properties();
    if (check.calls) {
      std::fprintf(stderr, "rvc: --calls pairs the events of one service: give one --input\n");
      return kUsage;
    }
    if (!topics.empty()) {
      std::fprintf(stderr, "rvc: --topic chooses a topic of a bag (--input bag:PATH)\n");
      return kUsage;
    }
    std::vector<transport::TransportOptions> per_input;
    auto named = sync.resolve(inputs, *app, input_option, typed, transports, per_input);
    std::vector<std::string> uris, names;
    size_t files = 0;
    for (const auto& in : named) {
      uris.push_back(in.uri);
      names.push_back(in.name);
      const std::string scheme = transport::scheme_of(in.uri);
      if (scheme == "mcap") {
        std::fprintf(stderr, "rvc: several topics of a bag: rvc check BAG --topic NAME=TOPIC ...\n");
        return kUsage;
      }
      files += scheme == "file";
    }
    if (files != 0 && files != named.size()) {
      std::fprintf(stderr, "rvc: inputs are all files or all topics, not a mix\n");
      return kUsage;
    }
    if (refuse_own_inputs(uris)) return kUsage;
    if (group.given())
      if (int status = join_group(uris)) return status;
    if (!forward_property.empty()) {
      std::fprintf(stderr, "rvc: --forward republishes the messages of one input; several inputs are checked as sets\n");
      return kUsage;
    }
    std::unique_ptr<transport::Sink> stats_sink;
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    if (int status = open_outputs(sinks, stats_sink)) return status;
    runtime::VerdictOutputs verdicts = make_verdicts(std::move(sinks));
    if (int status = open_enforcer(properties, verdicts, uris)) return status;
    if (int status = open_health(properties, verdicts, uris)) return status;
    runtime::PipelineOptions popts = check.pipeline_options();
    popts.position_name = files ? "line" : "seq";
    // --sets-output: what the properties saw, for `rvc check` to replay.
    std::vector<std::unique_ptr<transport::Sink>> set_sinks;
    if (!sets_output.empty()) {
      for (const auto& in : uris)
        if (refuse_own_input(sets_output, in)) return kUsage;
      set_sinks.push_back(transport::open_sink(sets_output, transports));
    }
    runtime::VerdictOutputs sets(std::move(set_sinks), true);
    runtime::SetCallback on_set;
    if (sets.size()) on_set = [&](std::string_view json, double) { sets.put_payload(json); };
    attach_results("", popts, verdicts);
    runtime::SyncedPipeline pipeline(properties, popts, named, sync.options(named),
                                     [&](const engine::Verdict& v) { verdicts.put(v); }, on_set);
    start_results(uris, properties);
    runtime::Feed* feed = &pipeline;
    if (group.given()) {
      const runtime::SyncOptions sync_options = sync.options(named);
      feed = &make_sharded(
          [&properties, popts, named, sync_options](const std::string& shard, engine::VerdictCallback on_verdict) {
            return std::make_unique<runtime::SyncedPipeline>(GroupFlags::shard_properties(properties, shard), popts,
                                                             named, sync_options, std::move(on_verdict));
          },
          verdicts);
    }
    runtime::LoopOptions lopts = loop_options(files != 0);
    lopts.join_mid_stream = group.given();
    clock.open_ros_clock(lopts, transports);
    lopts.input_names = names;
    lopts.input = SyncFlags::joined_names(named);
    for (const auto& uri : uris)  // rmw_zenoh: GIDs tell publishers apart: list each one's share
      if (transport::scheme_of(uri) == "rmw_zenoh") lopts.per_publisher = true;
    record_counters(lopts);
    attach_health(lopts);
    set_filter(lopts, uris);
    runtime::MonitorLoop loop(*feed, verdicts, stats_sink.get(), lopts);
    SyncFlags::Sources sources = SyncFlags::open_sources(named, per_input);
    if (group.subscribe_owned())  // per shard, not the whole key space (docs/fleet.md)
      for (size_t i = 0; i < named.size(); ++i) {
        sources.owned[i] = group.owned_source(named[i].uri);
        sources.list[i] = sources.owned[i].get();
      }
    install_stop_signals();
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %zu inputs (%s, sync %s) -> %zu output%s\n",
                 properties.size(), properties.size() == 1 ? "y" : "ies", named.size(), lopts.input.c_str(),
                 sync.policy.c_str(), verdicts.size(), verdicts.size() == 1 ? "" : "s");
    runtime::Outcome outcome = loop.run(sources.list);
    try {
      sets.finish();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: error: %s\n", e.what());
      outcome.runtime_failure = true;
    }
    finish_health(outcome, loop);
    return finish_results(outcome, loop);
  }

  runtime::LoopOptions loop_options(bool from_file) const {
    runtime::LoopOptions lopts;
    lopts.input = input;
    // A file has nothing more to come after its end.
    lopts.exit_on_eos = exit_on_eos || from_file;
    lopts.publishers = publishers;
    lopts.sequence_numbers = !from_file;
    lopts.idle_timeout = idle_timeout;
    lopts.stats_interval = stats_interval;
    lopts.queue_capacity = queue_capacity;
    using Handoff = runtime::LoopOptions::Handoff;
    lopts.handoff = handoff == "queue" ? Handoff::Queue : handoff == "inline" ? Handoff::Inline : Handoff::Auto;
    lopts.stop_requested = stop_requested;
    lopts.stats_requested = stats_requested;
    clock.apply(lopts, check.dense || check.calls, from_file);  // --calls: unanswered calls are due on the clock
    return lopts;
  }

  static bool ends_with(const std::string& s, const std::string& end) {
    return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
  }

  // --calls --type pkg/srv/Name --input dds:/svc: the call itself, read from
  // rmw_cyclonedds' rq/svcRequest and rr/svcReply (input 0 and 1), paired by
  // the request header (runtime/service_call_feed.hpp, docs/services.md).
  int run_service_wire(const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions popts,
                       runtime::VerdictOutputs& verdicts, transport::Sink* stats_sink) {
#ifdef RVC_HAVE_DDS
    if (transport::scheme_of(input) != "dds" || !transports.dds.ros2 || !forward_property.empty()) {
      std::fprintf(stderr, "rvc: --calls with a service type (%s) reads the request and reply topics of a ROS 2 "
                           "service over DDS: --input dds:/SERVICE (ROS 2 names, no --forward); for service events "
                           "give --type %s_Event\n", typed.type.c_str(), typed.type.c_str());
      return kUsage;
    }
    for (const auto& p : typed.msg_paths) typed.registry.add_search_path(p);
    const msg::MessageType& request = typed.registry.resolve(typed.type + "_Request");
    const msg::MessageType& response = typed.registry.resolve(typed.type + "_Response");
    const msg::MessageType request_wire = msg::with_request_header(request);
    const msg::MessageType response_wire = msg::with_request_header(response);
    const std::string service = transport::dds::dds_topic_name(input.substr(4), true).substr(3);  // "rt/a/b" -> "a/b"
    const std::vector<std::string> uris = {"dds:rq/" + service + "Request", "dds:rr/" + service + "Reply"};
    std::vector<transport::TransportOptions> per(2, transports);
    for (auto& t : per) t.dds.ros2 = false;  // the names above are DDS names already
    per[0].dds.ros_type = &request_wire;
    per[1].dds.ros_type = &response_wire;
    popts.type = nullptr;
    attach_results(input, popts, verdicts);
    runtime::Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) { verdicts.put(v); });
    runtime::ServiceCallFeed feed(pipeline, request, response, check.service_timeout, popts.max_reported);
    start_results({input}, properties);
    runtime::LoopOptions lopts = loop_options(false);
    clock.open_ros_clock(lopts, transports);
    lopts.input = input;
    lopts.input_names = {"request", "reply"};
    record_counters(lopts);
    attach_health(lopts);
    set_filter(lopts, uris);
    runtime::MonitorLoop loop(feed, verdicts, stats_sink, lopts);
    std::vector<std::unique_ptr<transport::Source>> owned;
    std::vector<transport::Source*> sources;
    for (size_t i = 0; i < uris.size(); ++i) {
      owned.push_back(transport::open_source(uris[i], per[i]));
      sources.push_back(owned.back().get());
    }
    install_stop_signals();
    std::fprintf(stderr, "rvc monitor: %zu propert%s on the calls of service %s (%s, %s) -> %zu output%s\n",
                 properties.size(), properties.size() == 1 ? "y" : "ies", input.c_str(), uris[0].c_str(),
                 uris[1].c_str(), verdicts.size(), verdicts.size() == 1 ? "" : "s");
    runtime::Outcome outcome = loop.run(sources);
    finish_health(outcome, loop);
    return finish_results(outcome, loop);
#else
    (void)properties;
    (void)popts;
    (void)verdicts;
    (void)stats_sink;
    std::fprintf(stderr, "rvc: this rvc was built without DDS\n");
    return kUsage;
#endif
  }

  int run() {
    if (!store.take_database(outputs)) return kUsage;
    if (outputs.empty()) outputs.push_back("-");
    if (int status = refuse_shared_files(written_targets())) return status;
    const bool bag = !SyncFlags::named(inputs) && is_bag_input(inputs.at(0));
    if (!instances.options(iopts)) return kUsage;
    if (instances.given() && (bag || SyncFlags::named(inputs) || check.calls || typed.given() || group.given() ||
                              !forward_property.empty() || (clock.clock != "auto" && clock.clock != "off"))) {
      std::fprintf(stderr, "rvc: --instances-by routes one JSON input's messages by a field; it does not take a bag, "
                           "several inputs, --calls, --type, --group, --forward or --clock (instances move with their own messages)\n");
      return kUsage;
    }
    if (!bag)
      if (int status = refuse_input_copies(outputs, inputs.at(0))) return status;
    if (handoff == "inline") {  // the receive thread checks: only a transport whose callbacks may block
      std::vector<std::string> uris;
      for (const std::string& in : inputs) {
        const auto eq = in.find('=');
        uris.push_back(SyncFlags::named(inputs) && eq != std::string::npos ? in.substr(eq + 1) : in);
      }
      if (clock.clock.rfind("ros=", 0) == 0) uris.push_back(clock.clock.substr(4));  // the /clock input too
      for (const std::string& uri : uris) {
        const std::string scheme = transport::scheme_of(uri);
        if ((scheme != "zenoh" && scheme != "rmw_zenoh") || group.given()) {
          std::fprintf(stderr, "rvc: --handoff inline checks each message on its transport's receive thread, which "
                               "only zenoh: and rmw_zenoh: inputs allow (%s): use --handoff queue or auto\n",
                       group.given() ? "not a --group's shard subscriptions" : ("not " + uri).c_str());
          return kUsage;
        }
      }
    }
    if (SyncFlags::named(inputs)) return run_synced();
    if (!bag && refuse_binary_file(inputs.at(0))) return kUsage;
    if (!bag && (!sync.stamps.empty() || app->count("--sync") || app->count("--pivot") || app->count("--lower-bound"))) {
      std::fprintf(stderr, "rvc: --stamp, --sync, --pivot and --lower-bound synchronize several inputs: give them as "
                           "--input NAME=URI (or several --topic of a bag)\n");
      return kUsage;
    }
    input = inputs.at(0);
    if (bag && !health.uris.empty()) {
      std::fprintf(stderr, "rvc: --diagnostics reports a live monitor's health; a bag (bag:) is checked at once: "
                           "drop --diagnostics\n");
      return kUsage;
    }
    auto properties = check.properties();
    if (refuse_own_inputs({input})) return kUsage;
    std::unique_ptr<transport::Sink> stats_sink;
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    if (int status = open_outputs(sinks, stats_sink)) return status;
    runtime::VerdictOutputs verdicts = make_verdicts(std::move(sinks));
    if (int status = open_enforcer(properties, verdicts, {input})) return status;
    if (!bag)
      if (int status = open_health(properties, verdicts, {input})) return status;
    runtime::PipelineOptions popts = check.pipeline_options();
    popts.position_name = "seq";
    if (bag) return run_bag(properties, popts, verdicts);
    if (!topics.empty()) {
      std::fprintf(stderr, "rvc: --topic chooses a topic of a bag (--input bag:PATH)\n");
      return kUsage;
    }
    transport::TransportOptions input_transports = transports;  // outputs stay std_msgs/String
    if (typed.given() && !TypeOptions::typed_scheme(input)) {
      std::fprintf(stderr, "rvc: --type reads typed samples from a dds: topic or CDR payloads from a zenoh: key (as "
                           "zenoh-bridge-ros2dds forwards them); %s inputs carry JSON\n",
                   transport::scheme_of(input).c_str());
      return kUsage;
    }
    try {
      typed.infer_from_graph(input, input_transports);  // rmw_zenoh: without --type
    } catch (const std::exception& e) {
      std::fprintf(stderr, "rvc: %s\n", e.what());
      return kUsage;
    }
    if (group.given())
      if (int status = join_group({input})) return status;
    if (check.calls && typed.given() && !ends_with(typed.type, "_Event")) {
      if (typed.type.find("/srv/") == std::string::npos) {  // a message type: no service to read
        std::fprintf(stderr, "rvc: --calls reads a service: --type pkg/srv/Name (its request and reply topics) or "
                             "pkg/srv/Name_Event (its introspection events); %s is not a service type\n",
                     typed.type.c_str());
        return kUsage;
      }
      return run_service_wire(properties, popts, verdicts, stats_sink.get());
    }
    popts.type = typed.resolve(input_transports);
    // --calls: the input's events are paired into calls; the properties read the calls (JSON).
    const msg::MessageType* event_type = popts.type;
    if (check.calls && event_type)
      if (std::string why = runtime::not_a_service_event(*event_type, "input " + input); !why.empty()) {
        std::fprintf(stderr, "rvc: %s\n", why.c_str());
        return kUsage;
      }
    if (check.calls) {
      if (!forward_property.empty()) {
        std::fprintf(stderr, "rvc: --forward republishes the input's messages; with --calls the properties check calls\n");
        return kUsage;
      }
      popts.type = nullptr;
    }
    attach_results(input, popts, verdicts);
    runtime::Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) { verdicts.put(v); });
    std::unique_ptr<runtime::InstancesFeed> instance_feed;
    iopts.tick_at_end = clock.ticks_at_end(check.dense);  // an expiring instance ends as its sub-trace would
    if (instances.given()) instance_feed = std::make_unique<runtime::InstancesFeed>(properties, popts, verdicts, iopts);
    std::unique_ptr<runtime::ServiceCallFeed> call_feed;
    if (check.calls)
      call_feed = std::make_unique<runtime::ServiceCallFeed>(pipeline, event_type, check.service_timeout,
                                                              popts.max_reported);
    start_results({input}, properties);

    runtime::LoopOptions lopts = loop_options(transport::scheme_of(input) == "file");
    lopts.join_mid_stream = group.given();
    lopts.per_publisher = transport::scheme_of(input) == "rmw_zenoh";  // GIDs: loss per publisher
    clock.open_ros_clock(lopts, transports);
    record_counters(lopts);
    attach_health(lopts);
    set_filter(lopts, {input});
    // --forward: what passes the property goes on to <input>_mon.
    std::unique_ptr<runtime::Forwarder> forwarder;
    if (!forward_property.empty()) {
      if (int status = check_property_name(forward_property, properties, "--forward")) return status;
      const std::string to = forward_to.empty() ? runtime::monitored_topic(input) : forward_to;
      if (refuse_own_input(to, input)) return kUsage;
      forwarder = std::make_unique<runtime::Forwarder>(pipeline, forward_property,
                                                       transport::open_sink(to, input_transports), verdicts);
      std::fprintf(stderr, "rvc monitor: messages that keep %s true go on to %s\n", forward_property.c_str(),
                   to.c_str());
    }
    if (group.given())
      make_sharded(
          [&properties, popts](const std::string& shard, engine::VerdictCallback on_verdict) {
            return std::make_unique<runtime::Pipeline>(GroupFlags::shard_properties(properties, shard), popts,
                                                       std::move(on_verdict));
          },
          verdicts);
    runtime::Feed& feed = sharded     ? static_cast<runtime::Feed&>(*sharded)
                          : instance_feed ? static_cast<runtime::Feed&>(*instance_feed)
                          : forwarder ? static_cast<runtime::Feed&>(*forwarder)
                          : call_feed ? static_cast<runtime::Feed&>(*call_feed)
                                      : pipeline;
    runtime::MonitorLoop loop(feed, verdicts, stats_sink.get(), lopts);

    auto source = group.subscribe_owned() ? group.owned_source(input) : transport::open_source(input, input_transports);
    install_stop_signals();
    std::fprintf(stderr, "rvc monitor: %zu propert%s on %s -> %zu output%s\n", properties.size(),
                 properties.size() == 1 ? "y" : "ies", input.c_str(), verdicts.size(), verdicts.size() == 1 ? "" : "s");
    runtime::Outcome outcome = loop.run(*source);
    if (forwarder) {
      try {
        forwarder->finish();
      } catch (const std::exception& e) {
        std::fprintf(stderr, "rvc: error: %s\n", e.what());
        outcome.runtime_failure = true;
      }
    }
    finish_health(outcome, loop);
    return finish_results(outcome, loop);
  }
};

}  // namespace

Runner register_monitor(CLI::App& app) {
  auto cmd = std::make_shared<MonitorCommand>();
  CLI::App* sub = app.add_subcommand("monitor", "Monitor a topic: subscribe, check properties, publish verdicts");
  cmd->check.add_to(*sub);
  cmd->app = sub;
  cmd->input_option =
      sub->add_option("--input,-i", cmd->inputs,
                      "Endpoint to monitor: zenoh:KEYEXPR, dds:TOPIC, file:PATH, - or bag:BAG (a ROS 2 bag: .mcap, .db3 or a bag folder; mcap:BAG too); "
                      "several as NAME=URI (repeatable), synchronized by --sync, tested as {NAME.field}")
          ->required();
  sub->add_option("--output,-o", cmd->outputs,
                  "Where verdicts go (repeatable): zenoh:KEY, dds:TOPIC, file:PATH, - (default); also a results "
                  "database: sqlite:PATH or postgresql://... (docs/results.md)")
      ->allow_extra_args(false);
  cmd->store.add_to(*sub);
  cmd->health.add_to(*sub);
  cmd->group.add_to(*sub);
  cmd->instances.add_to(*sub);
  sub->add_option("--allow", cmd->filter_options.allow,
                  "Filter (repeatable): only messages whose key (a zenoh: sample's own key) or topic matches one of "
                  "these patterns reach the monitor; '*' one chunk, '**' any chunks (docs/filter.md)");
  sub->add_option("--deny", cmd->filter_options.deny,
                  "Filter (repeatable): messages whose key or topic matches are kept from the monitor (wins over --allow)");
  sub->add_option("--project", cmd->filter_options.project,
                  "Filter (repeatable): keep only these fields of each JSON message (dotted paths) for the monitor, "
                  "the witness window and --forward")
      ->delimiter(',');
  sub->add_option("--forward", cmd->forward_property,
                  "ROSMonitoring's filter: republish each message after which PROPERTY still holds on <input>_mon "
                  "(or --forward-to); violating messages are held back");
  sub->add_option("--forward-to", cmd->forward_to, "Where --forward republishes (default: the input URI + _mon)");
  sub->add_option("--on-violation", cmd->on_violation,
                  "Enforcer (repeatable): when PROPERTY becomes violated, publish PAYLOAD on URI, e.g. "
                  "p1=zenoh:vehicle/hazard:{\"on\":true} (docs/enforcer.md)");
  sub->add_option("--debounce", cmd->debounce,
                  "Enforcer: at least S seconds between two commands of one --on-violation")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  sub->add_option("--command-type", cmd->command_type,
                  "Enforcer: send commands on dds:/zenoh: as CDR samples of this type (their PAYLOAD is its JSON), e.g. "
                  "std_msgs/msg/Bool");
  sub->add_flag("--exit-on-eos", cmd->exit_on_eos,
                "Exit after the publisher's end-of-stream marker (ending any other way is then exit 6)");
  sub->add_option("--publishers", cmd->publishers,
                  "With --exit-on-eos: wait for the end-of-stream markers of at least N publishers (and of every "
                  "publisher seen)")
      ->check(in_range(1, 100000))
      ->capture_default_str();
  sub->add_option("--idle-timeout", cmd->idle_timeout,
                  "Give up after S seconds without any message (0: wait forever); with --exit-on-eos that is exit 6")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--stats-interval", cmd->stats_interval, "Print counters every S seconds (also on SIGUSR1)")
      ->check(in_range(0, kMaxSeconds, "seconds"));
  sub->add_option("--stats-output", cmd->stats_output, "Also publish the counters (JSON) to this endpoint");
  sub->add_option("--verdict-type", cmd->verdict_type,
                  "Publish verdicts on dds:/zenoh: outputs as this ROS 2 type (rvc_msgs/msg/Verdict: time, property, "
                  "value) instead of std_msgs/String JSON; files still get JSON lines");
  sub->add_option("--sets-output", cmd->sets_output,
                  "Several inputs: also publish each synchronized set (JSON, as rvc sync) to this endpoint");
  sub->add_option("--wait-subscribers", cmd->wait_subscribers,
                  "Before reading the input, wait for this many subscribers on each zenoh:/dds: output")
      ->check(in_range(0, 100000))
      ->capture_default_str();
  sub->add_option("--wait-timeout", cmd->wait_timeout, "Seconds to wait for them")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
  cmd->typed.add_to(*sub,
                    "Message type of the input's CDR payloads: ROS 2 pkg/msg/Name (`rvc msg list`, `rvc msg show`) or a DDS IDL name from --msg-path; "
                    "several inputs: after the --input it is for, or NAME=pkg/msg/Name");
  sub->get_option("--msg-path")
      ->description("Folder of .msg/.idl definitions (a ROS 2 share/ tree or a plain folder), or one .idl file "
                    "(repeatable): for --type, and for --input bag:BAG the types its schemas name but do not define");
  cmd->sync.add_to(*sub);
  sub->add_option("--topic", cmd->topics,
                  "With --input bag:BAG: the topic to check (if the bag holds several); repeatable: NAME=TOPIC, "
                  "synchronized by --sync");
  cmd->clock.add_live(*sub);
  sub->add_option("--queue", cmd->queue_capacity, "Messages buffered between transport and engine")
      ->check(in_range(1, kMaxQueue))
      ->capture_default_str();
  sub->add_option("--handoff", cmd->handoff,
                  "How messages reach the checker: inline (on the transport's receive thread, no queue and no "
                  "wake-up between message and verdict: the lowest latency; Zenoh inputs), queue (a bounded queue "
                  "to the checker's thread), auto (inline where every input allows it, i.e. Zenoh; DDS and files "
                  "queue)")
      ->check(CLI::IsMember({"auto", "queue", "inline"}))
      ->capture_default_str();
  add_transport_options(*sub, cmd->transports);
  sub->footer(
      "Exit status: 0 all held, 1 a property was violated, 2 usage/spec error, 3 messages rejected (or dropped as\n"
      "late), 4 messages lost, 5 runtime failure (an output could not be written), 6 incomplete (nothing received\n"
      "or checked, or no end-of-stream marker with --exit-on-eos).\n"
      "Example: rvc monitor --spec 'historically({emergency} -> once[0:1]{hazard_lights})' \\\n"
      "           --input zenoh:vehicle/status --output zenoh:rv/verdicts");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
