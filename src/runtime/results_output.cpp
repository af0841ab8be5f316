#include "runtime/results_output.hpp"

#include <cstdio>

#include "spec/spec_error.hpp"

namespace rvc::runtime {

ResultsOutput::ResultsOutput(const std::string& uri, store::StoreOptions options)
    : store_(std::make_unique<store::ResultsStore>(store::open_database_when_reachable(uri), std::move(options))) {}

void ResultsOutput::attach(const std::string& input_name, PipelineOptions& options, VerdictOutputs& outputs) {
  store::ResultsStore* store = store_.get();
  options.input_name = input_name;
  options.on_message = [store](std::string_view input, std::string_view text, uint64_t position) {
    store->on_message(input, text, position);
  };
  VerdictOutputs* out = &outputs;
  outputs.observe([store, out](const engine::Verdict& v) {
    // A parametric instance's verdict (--instances-by; mark ,"instance":{..}):
    // stored under "NAME {..}", so each instance has its own verdict changes.
    constexpr std::string_view kInstance = ",\"instance\":";
    if (const std::string_view m = out->mark(); m.rfind(kInstance, 0) == 0) {
      const std::string name = v.property + " " + std::string(m.substr(kInstance.size()));
      store->on_verdict(name, v.time, v.value, v.explanation, v.known_at);
      return;
    }
    store->on_verdict(v.property, v.time, v.value, v.explanation, v.known_at);
  });
}

void ResultsOutput::finish(Outcome& outcome, const std::string& reason, const std::string& final_counters) {
  if (!store_->end_run(outcome.exit_code(), reason, final_counters)) outcome.runtime_failure = true;
  const store::StoreStats s = store_->stats();
  // Rows the database refused are results it does not hold: not a success.
  if (s.refused) {
    std::fprintf(stderr, "rvc: results database %s refused %llu row%s: not stored (the first: %s)\n",
                 describe().c_str(), static_cast<unsigned long long>(s.refused), s.refused == 1 ? "" : "s",
                 s.first_refusal.c_str());
    outcome.runtime_failure = true;
  }
  std::fprintf(stderr, "rvc: results in %s, run %s: %llu verdict changes, %llu violations%s\n", describe().c_str(),
               run_id().c_str(), static_cast<unsigned long long>(s.verdicts),
               static_cast<unsigned long long>(s.violations),
               s.lost ? " (some lost)" : s.left_in_spool ? " (some still in the spool)" : "");
}

void check_specs(const std::vector<engine::PropertySpec>& properties, bool dense) {
  engine::Checker checker(dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete, false, nullptr);
  for (const auto& p : properties) {
    try {
      checker.add_property(p);
    } catch (const spec::SpecError& e) {
      throw spec::SpecError("in property '" + p.name + "': " + e.message(), e.source(), e.column());
    }
  }
}

store::RunInfo run_info(const std::string& command, const std::vector<std::string>& inputs,
                        const std::vector<engine::PropertySpec>& properties, bool dense) {
  store::RunInfo info;
  info.command = command;
  info.inputs = inputs;
  info.time_model = dense ? "dense" : "discrete";
  for (const auto& p : properties) info.properties.emplace_back(p.name, p.spec);
  return info;
}

}  // namespace rvc::runtime
