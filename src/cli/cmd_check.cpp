// rvc check: run properties over a JSON-lines trace (file or stdin), print
// verdicts as JSON lines, and exit non-zero if a property was violated. Runs
// on the same runtime as `rvc monitor` (src/runtime).
#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <limits>
#include <memory>

#include "cli/check_options.hpp"
#include "cli/instance_options.hpp"
#include "cli/clock_options.hpp"
#include "cli/commands.hpp"
#include "cli/output_sinks.hpp"
#include "cli/signals.hpp"
#include "cli/store_options.hpp"
#include "io/json_writer.hpp"
#include "cli/sync_options.hpp"
#include "msg/type_registry.hpp"
#include "runtime/check_stream.hpp"
#include "runtime/instances_feed.hpp"
#include "cli/bag_run.hpp"
#include "runtime/check_bag.hpp"
#include "transport/rosbag2/bag_reader.hpp"
#include "transport/file_endpoint.hpp"
#include "transport/transport_options.hpp"

namespace rvc::cli {
namespace {

std::string strip_file_scheme(const std::string& uri) {
  if (uri.rfind("file:", 0) == 0) return uri.substr(5);
  if (uri.rfind("mcap:", 0) == 0) return uri.substr(5, uri.rfind("?inputs=") - 5);  // verdicts as MCAP (docs/mcap-output.md)
  return uri;
}

// The one verdict output of rvc check: JSON lines (a path, file:PATH, -) or mcap:PATH.
std::unique_ptr<transport::Sink> open_verdict_sink(const std::string& output) {
  if (output.rfind("mcap:", 0) == 0) return transport::open_sink(output, {});
  return std::make_unique<transport::FileSink>(strip_file_scheme(output));
}

struct CheckCommand {
  CheckOptions check;
  ClockFlags clock;  // --clock auto|off: a tick at the recording's end
  std::string input;
  std::vector<std::string> outputs;  // verdict files (one) and a results database
  std::string output = "-";
  StoreFlags store;
  bool summary = false;
  bool stats = false;  // --stats: the counters as one JSON line on stderr, as the monitor's
  std::vector<std::string> topics;  // --topic: which topic(s) of a bag
  std::vector<std::string> msg_paths;  // --msg-path: definitions a bag's schemas leave out
  SyncFlags sync;                   // several topics
  msg::TypeRegistry registry;  // types from a bag's schemas
  InstanceFlags instances;  // --instances-by: one monitor instance per key value (docs/semantics.md)
  runtime::InstanceOptions iopts;

  int run() {
    if (!store.take_database(outputs)) return kUsage;
    if (outputs.size() > 1) {
      std::fprintf(stderr, "rvc: check writes verdicts to one file (and a results database): %zu files given\n",
                   outputs.size());
      return kUsage;
    }
    if (!outputs.empty()) output = outputs[0];
    {
      std::vector<std::pair<std::string, std::string>> written{{"--output", output}};
      if (!store.database.empty()) written.emplace_back("the results database", store.database);
      if (!store.options.spool.empty()) written.emplace_back("--spool", store.options.spool);
      if (int status = refuse_shared_files(written)) return status;
    }
    auto properties = check.properties();
    const std::string path = strip_file_scheme(input), opath = strip_file_scheme(output);
    if (opath != "-" && runtime::same_regular_file(path, opath)) {
      std::fprintf(stderr, "rvc: --output '%s' is the trace being read: refusing to overwrite it\n", opath.c_str());
      return kUsage;
    }
    // A bag: named so (bag:PATH, mcap:PATH) or found by its content (an MCAP
    // or rosbag2 sqlite3 file, a folder with metadata.yaml), as `ros2 bag` takes it.
    const bool bag = input.rfind("mcap:", 0) == 0 || input.rfind("bag:", 0) == 0;
    if (!instances.options(iopts)) return kUsage;
    if (instances.given() && (bag || (path != "-" && transport::is_bag(path)) || check.calls)) {
      std::fprintf(stderr, "rvc: --instances-by routes a JSON-lines trace's messages by a field; it does not "
                           "take a bag, --calls or synchronized inputs\n");
      return kUsage;
    }
    if (bag || (path != "-" && transport::is_bag(path)))
      return run_bag(properties, bag ? input.substr(input.find(':') + 1) : path, opath);
    if (path != "-") {
      // An empty or cut-short .mcap/.db3 is a bag that failed, not an empty trace.
      if (const std::string cut = transport::truncated_bag(path); !cut.empty()) {
        std::fprintf(stderr, "rvc: bag '%s' is %s\n", path.c_str(), cut.c_str());
        return kUsage;
      }
      if (const std::string what = transport::binary_signature(path); !what.empty()) {
        std::fprintf(stderr, "rvc: trace '%s' is %s, not JSON lines (rvc check reads JSON lines and ROS 2 bags)\n",
                     path.c_str(), what.c_str());
        return kUsage;
      }
    }
    if (int status = refuse_input_copies({output}, path == "-" ? "stdin" : path)) return status;
    if (check.calls) {
      std::fprintf(stderr, "rvc: --calls pairs the service events of a bag's topic (or a live input: rvc monitor "
                           "--calls); for JSON lines pipe them through `rvc calls` into `rvc check -`\n");
      return kUsage;
    }
    if (!topics.empty() || !msg_paths.empty()) {
      std::fprintf(stderr, "rvc: %s a bag (MCAP, sqlite3 or a bag folder); '%s' is a JSON-lines trace\n",
                   topics.empty() ? "--msg-path gives the message definitions of" : "--topic chooses a topic of",
                   path.c_str());
      return kUsage;
    }
    int fd = 0;
    if (path != "-") {
      fd = ::open(path.c_str(), O_RDONLY);
      if (fd < 0) {
        std::fprintf(stderr, "rvc: cannot open trace '%s'\n", path.c_str());
        return kUsage;
      }
    }
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    sinks.push_back(open_verdict_sink(output));
    runtime::VerdictOutputs outputs(std::move(sinks), !check.dense);
    runtime::PipelineOptions popts = check.pipeline_options();
    // A bad spec ends the run before the database is opened: a refused run
    // creates no results file.
    if (!store.database.empty()) runtime::check_specs(properties, check.dense);
    auto results = store.open();
    if (results) results->attach(input, popts, outputs);
    if (instances.given()) return run_instances(properties, popts, outputs, results.get(), fd, path);
    runtime::Pipeline pipeline(properties, popts, [&](const engine::Verdict& v) { outputs.put(v); });
    if (results) results->start(runtime::run_info(command_line(), {input}, properties, check.dense));
    io::ReaderOptions ropts;
    ropts.max_line_bytes = check.max_message_size;
    // SIGINT/SIGTERM end the input where it is, as `rvc monitor`'s: what was
    // read is checked, verdicts and results are flushed, the run is closed.
    install_stop_signals();
    end_input_on_stop(fd);
    // Reading stdin: show each verdict as soon as it is known.
    runtime::Outcome outcome = runtime::check_stream(fd, pipeline, outputs, ropts, path == "-",
                                                             clock.ticks_at_end(check.dense));
    end_input_on_stop(-1);
    if (fd != 0) ::close(fd);
    report(pipeline.stats(), pipeline.violations());
    const bool stopped = stop_requested();
    if (stopped) {
      // Not a pass: the input was cut (monitor's status for a stop signal).
      std::fprintf(stderr, "rvc: stopped by a signal after %llu messages: %s was not read to its end\n",
                   static_cast<unsigned long long>(pipeline.stats().accepted + pipeline.stats().rejected),
                   path == "-" ? "stdin" : path.c_str());
      outcome.incomplete = true;
    }
    if (stats) {
      io::JsonObject counters;
      counters.add("input", input);
      runtime::add_run_counters(counters, pipeline, outputs.count());
      std::fprintf(stderr, "%s\n", counters.str().c_str());
    }
    if (results)
      results->finish(outcome, stopped ? "signal" : "end of input",
                      counters_json(pipeline.stats(), pipeline.violations(), pipeline.last_stamp()));
    return outcome.exit_code();
  }

  // --instances-by: one Pipeline per key value behind one reader (runtime/instances_feed.hpp).
  int run_instances(const std::vector<engine::PropertySpec>& properties, const runtime::PipelineOptions& popts,
                    runtime::VerdictOutputs& outputs, runtime::ResultsOutput* results, int fd, const std::string& path) {
    iopts.tick_at_end = clock.ticks_at_end(check.dense);  // an expiring instance ends as its sub-trace would
    runtime::InstancesFeed feed(properties, popts, outputs, iopts);
    if (results) results->start(runtime::run_info(command_line(), {input}, properties, check.dense));
    io::ReaderOptions ropts;
    ropts.max_line_bytes = check.max_message_size;
    install_stop_signals();
    end_input_on_stop(fd);
    const bool live = path == "-", tick = clock.ticks_at_end(check.dense);
    if (live) ropts.after_chunk = [&outputs] { outputs.idle(); };
    runtime::Outcome outcome = runtime::run_check(feed, outputs, [&](runtime::Outcome& o) {
      std::string error;
      if (!io::read_jsonl(fd, feed, ropts, error)) {
        std::fprintf(stderr, "rvc: error: %s\n", error.c_str());
        o.runtime_failure = true;
        return;
      }
      if (tick) feed.tick_each_at_end();
    });
    end_input_on_stop(-1);
    if (fd != 0) ::close(fd);
    report(feed.stats(), feed.violations());
    if (feed.lost() > 0)
      std::fprintf(stderr, "rvc: %llu messages dropped: --max-instances %zu refused %llu new keys\n",
                   static_cast<unsigned long long>(feed.lost()), iopts.max_instances,
                   static_cast<unsigned long long>(feed.refused_keys()));
    const bool stopped = stop_requested();
    if (stopped) {
      std::fprintf(stderr, "rvc: stopped by a signal: %s was not read to its end\n", live ? "stdin" : path.c_str());
      outcome.incomplete = true;
    }
    if (stats) {
      io::JsonObject counters;
      counters.add("input", input);
      runtime::add_run_counters(counters, feed, outputs.count());
      feed.add_stats(counters);
      std::fprintf(stderr, "%s\n", counters.str().c_str());
    }
    if (results)
      results->finish(outcome, stopped ? "signal" : "end of input", counters_json(feed.stats(), feed.violations(), feed.last_stamp()));
    return outcome.exit_code();
  }

  // A ROS 2 bag: its types from the bag's own schemas.
  int run_bag(const std::vector<engine::PropertySpec>& properties, const std::string& path,
              const std::string& opath) {
    for (const auto& dir : msg_paths) registry.add_search_path(dir);
    std::vector<std::unique_ptr<transport::Sink>> sinks;
    sinks.push_back(open_verdict_sink(output));
    runtime::VerdictOutputs outputs(std::move(sinks), !check.dense);
    runtime::PipelineOptions popts = check.pipeline_options();
    auto results = store.open();
    if (results) {
      // A bag's properties are checked as the run starts: a bad spec ends it
      // before any result, as it does without a database.
      runtime::check_specs(properties, check.dense);
      results->attach(input, popts, outputs);
      results->start(runtime::run_info(command_line(), {input}, properties, check.dense));
    }
    if (check.calls && topics.size() > 1) {
      std::fprintf(stderr, "rvc: --calls pairs the events of one service topic (--topic /svc/_service_event)\n");
      return kUsage;
    }
    // --calls: a tick at the recording's end also in discrete time, so a request unanswered by then is made
    BagRun run = cli::run_bag(path, topics, properties, popts, sync, registry, outputs,
                              clock.ticks_at_end(check.dense || check.calls), check.calls_timeout());
    if (summary) std::fprintf(stderr, "rvc check: %s, %s\n", path.c_str(), run.description.c_str());
    report(run.stats, run.violations);
    if (stats) std::fprintf(stderr, "%s\n", run.counters_json(input, outputs.count()).c_str());
    if (results) results->finish(run.outcome, run.stopped ? "signal" : "end of bag", counters_json(run.stats, run.violations));
    return run.outcome.exit_code();
  }

  // The run's counters for the results store.
  // `stream_time`: dense time's last stamp (NaN: none, or discrete time), so the dashboard's
  // timeline reaches the last instant checked.
  static std::string counters_json(const runtime::PipelineStats& s, uint64_t violations,
                                   double stream_time = std::numeric_limits<double>::quiet_NaN()) {
    io::JsonObject out;
    out.add("checked", s.accepted).add("rejected", s.rejected).add("warnings", s.warnings).add("violations", violations);
    if (stream_time == stream_time) out.add("stream_time", stream_time);
    return out.str();
  }

  void report(const runtime::PipelineStats& s, uint64_t violations) const {
    if (summary || s.rejected > 0) {
      std::fprintf(stderr, "rvc: %llu messages checked, %llu rejected, %llu warnings; %s\n",
                   static_cast<unsigned long long>(s.accepted), static_cast<unsigned long long>(s.rejected),
                   static_cast<unsigned long long>(s.warnings),
                   violations ? "a property was violated" : "no property was violated");
    }
  }
};

}  // namespace

Runner register_check(CLI::App& app) {
  auto cmd = std::make_shared<CheckCommand>();
  CLI::App* sub = app.add_subcommand("check", "Check properties over a JSON-lines trace (file or - for stdin) or a ROS 2 bag (MCAP, sqlite3, bag folder)");
  cmd->check.add_to(*sub);
  sub->add_option("trace", cmd->input, "Trace: PATH, file:PATH or - for stdin (JSON lines), or a ROS 2 bag: a .mcap or .db3 file or a bag folder "
                  "(found by content; bag:PATH says so)")
      ->required();
  sub->add_option("--topic", cmd->topics,
                  "The topic of a bag to check (needed when the bag holds several); repeatable: NAME=TOPIC (or TOPIC, "
                  "named by its last part), synchronized by --sync, tested as {NAME.field}");
  sub->add_option("--msg-path", cmd->msg_paths,
                  "A bag's types that its schemas name but do not define: a folder of .msg/.idl definitions (a ROS 2 "
                  "share/ tree or a plain folder) or one .idl file (repeatable)");
  cmd->sync.add_to(*sub);
  cmd->clock.add_offline(*sub);
  sub->add_option("--output,-o", cmd->outputs,
                  "Where verdicts go: PATH, file:PATH or - (stdout, the default), or mcap:PATH (an MCAP file for "
                  "Foxglove, docs/mcap-output.md); repeatable for results databases: "
                  "sqlite:PATH or postgresql://... (docs/results.md)");
  cmd->store.add_to(*sub);
  cmd->instances.add_to(*sub);
  sub->add_flag("--summary", cmd->summary, "Print message counts to stderr at the end");
  sub->add_flag("--stats", cmd->stats,
                "Print the counters as one JSON line on stderr at the end (received, checked, rejected, dropped by "
                "reason, warnings, verdicts, violations), as rvc monitor does");
  sub->footer(
      "Exit status: 0 all properties held, 1 a property was violated, 2 usage or spec error, 3 messages were\n"
      "rejected (or dropped: late, --max-instances), 5 runtime failure (the trace could not be read, verdicts or results could\n"
      "not be written), 6 nothing was checked (an empty trace, every message rejected or unmatched) or stopped\n"
      "by SIGINT/SIGTERM before the end of the trace (what was read is checked and stored).\n"
      "Example: rvc check --spec 'historically({emergency} -> once[0:1]{hazard_lights})' trace.jsonl");
  return [cmd] { return cmd->run(); };
}

}  // namespace rvc::cli
