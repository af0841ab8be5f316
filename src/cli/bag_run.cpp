#include "cli/bag_run.hpp"

#include <memory>
#include <stdexcept>
#include <string>

#include "cli/signals.hpp"
#include "runtime/service_call_feed.hpp"

namespace rvc::cli {

BagRun run_bag(const std::string& path, const std::vector<std::string>& topics,
               const std::vector<engine::PropertySpec>& properties, runtime::PipelineOptions options,
               const SyncFlags& sync, msg::TypeRegistry& registry, runtime::VerdictOutputs& outputs,
               bool tick_at_end, double calls_timeout) {
  BagRun run;
  install_stop_signals();
  options.position_name = "message";
  auto on_verdict = [&](const engine::Verdict& v) { outputs.put(v); };
  if (topics.size() <= 1 && (topics.empty() || topics[0].find('=') == std::string::npos || topics[0][0] == '/')) {
    runtime::BagInput bag = runtime::select_bag_topic(path, topics.empty() ? "" : topics[0], registry);
    runtime::set_size_cap(bag, options);
    const bool calls = calls_timeout > 0;
    if (calls && bag.type)
      if (std::string why = runtime::not_a_service_event(*bag.type, "topic " + bag.topic); !why.empty())
        throw std::invalid_argument(why);
    options.type = calls ? nullptr : bag.type;  // --calls: the properties read the calls, JSON
    runtime::Pipeline pipeline(properties, options, on_verdict);
    std::unique_ptr<runtime::ServiceCallFeed> call_feed;
    if (calls) call_feed = std::make_unique<runtime::ServiceCallFeed>(pipeline, bag.type, calls_timeout, options.max_reported);
    runtime::Feed& feed = call_feed ? static_cast<runtime::Feed&>(*call_feed) : pipeline;
    run.messages = bag.messages;
    run.topic = bag.topic;
    run.description = "topic " + bag.topic + " (" + (bag.type ? bag.type->full_name() : std::string("JSON")) + ", " +
                      std::to_string(bag.messages) + " messages" + (calls ? ", paired into calls" : "") + ")";
    uint64_t skipped = 0;
    run.outcome = runtime::check_bag({bag}, feed, outputs, skipped, stop_requested, tick_at_end);
    run.stopped = stop_requested();
    run.stats = feed.stats();
    run.stats.rejected += skipped;  // the bag's bad records: rejected input like a malformed message
    run.violations = feed.violations();
    run.received = feed.received() + skipped;  // a bad record was read and rejected: counts add up
    feed.add_dropped(run.dropped);
    if (call_feed) {
      run.has_calls = true;
      run.calls = call_feed->call_counts();
    }
    // Samples only too large say nothing about the definition they were read with.
    if (run.stats.accepted == 0 && run.stats.rejected > skipped + run.stats.oversized) runtime::hint_bag_definition(bag);
    return run;
  }
  std::vector<runtime::BagInput> bags;
  std::vector<runtime::SyncInput> inputs = runtime::select_bag_topics(path, topics, registry, bags);
  sync.apply_stamps(inputs);
  for (auto& b : bags) runtime::set_size_cap(b, options);
  runtime::SyncedPipeline pipeline(properties, options, inputs, sync.options(inputs), on_verdict);
  for (size_t i = 0; i < bags.size(); ++i) {
    run.messages += bags[i].messages;
    run.topic += (i ? "," : "") + bags[i].topic;
    run.description += std::string(i ? ", " : "topics ") + inputs[i].name + "=" + bags[i].topic + " (" +
                       (bags[i].type ? bags[i].type->full_name() : std::string("JSON")) + ", " +
                       std::to_string(bags[i].messages) + ")";
  }
  run.description += std::string(", sync ") + sync::to_string(sync.options(inputs).policy);
  uint64_t skipped = 0;
  run.outcome = runtime::check_bag(bags, pipeline, outputs, skipped, stop_requested, tick_at_end);
  run.stopped = stop_requested();
  run.stats = pipeline.stats();
  run.stats.rejected += skipped;
  run.violations = pipeline.violations();
  run.received = pipeline.received() + skipped;
  pipeline.add_dropped(run.dropped);
  return run;
}

std::string BagRun::counters_json(const std::string& input, uint64_t verdicts) const {
  io::JsonObject out;
  out.add("input", input)
      .add("topic", topic)
      .add("messages", messages)
      .add("received", received)
      .add("checked", stats.accepted)
      .add("rejected", stats.rejected)
      .add("dropped", dropped)
      .add("warnings", stats.warnings)
      .add("verdicts", verdicts)
      .add("violations", violations);
  if (has_calls) out.add("calls", calls);
  return out.str();
}

}  // namespace rvc::cli
