// Properties over a ROS 2 bag, as `rvc check BAG` and `rvc monitor --input
// mcap:BAG` both run it: one topic through a Pipeline, several topics
// (--topic NAME=TOPIC, repeatable) synchronized through a SyncedPipeline.
#pragma once

#include <string>
#include <vector>

#include "cli/sync_options.hpp"
#include "io/json_writer.hpp"
#include "msg/type_registry.hpp"
#include "runtime/check_bag.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::cli {

struct BagRun {
  runtime::Outcome outcome;
  runtime::PipelineStats stats;
  uint64_t violations = 0;
  uint64_t messages = 0;    // of the chosen topics
  uint64_t received = 0;    // of those, read (all of them unless the bag broke off), damaged records included
  io::JsonObject dropped;   // by the synchronizer, by reason
  std::string topic;        // the chosen topic (several: joined by ",")
  std::string description;  // "topic /a (pkg/msg/T, 12 messages)", or the inputs
  bool stopped = false;     // a stop signal ended the bag before its end
  io::JsonObject calls;     // --calls: the service events' counts (runtime/service_call_feed.hpp)
  bool has_calls = false;

  // The run's counters as one JSON object, the fields of the monitor's line
  // (received = checked + rejected + dropped), for `check --stats` and `monitor`.
  std::string counters_json(const std::string& input, uint64_t verdicts) const;
};

// Throws as select_bag_topic(s) for a bad choice of topics; `sync` applies
// with several topics. SIGINT/SIGTERM end the bag where it is (what was read
// is checked; the outcome is incomplete), as they end every other input.
// `tick_at_end` (dense time, --clock auto): the bag's own clock ticks at its
// end (runtime::check_bag). `calls_timeout` > 0 (--calls): the one topic is a
// service's events, paired into calls that the properties check.
BagRun run_bag(const std::string& path, const std::vector<std::string>& topics,
               const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions options,
               const SyncFlags& sync, msg::TypeRegistry& registry, runtime::VerdictOutputs& outputs,
               bool tick_at_end = false, double calls_timeout = 0);

}  // namespace rvc::cli
