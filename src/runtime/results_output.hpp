// `--output sqlite:PATH` / `--output postgresql://...`: a results store
// wired into a run. It sees each message before the monitors do (witness
// window), every verdict (changes and violations), the counters while the
// run lasts, and the run's end; `rvc check` and `rvc monitor` attach it the
// same way.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "engine/checker.hpp"
#include "runtime/exit_status.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/verdict_outputs.hpp"
#include "store/results_store.hpp"

namespace rvc::runtime {

class ResultsOutput {
 public:
  // Opens the database (creating its tables) and starts the writer. Throws
  // store::DbError when the database cannot be opened at all.
  ResultsOutput(const std::string& uri, store::StoreOptions options);

  // Hooks the pipeline's messages and the outputs' verdicts. `options` must
  // be the ones the pipeline is built with.
  void attach(const std::string& input_name, PipelineOptions& options, VerdictOutputs& outputs);
  // Records the run: once the pipeline is built (its specs are valid), before
  // the first message.
  void start(const store::RunInfo& run) { store_->begin_run(run); }
  void counters(const std::string& json) { store_->on_counters(json); }
  // After the run: its end, then waits for the writer. A store that could
  // not write everything (the database stayed away, rows it refused, a spool
  // that could not be written) is a runtime failure.
  void finish(Outcome& outcome, const std::string& reason, const std::string& final_counters);

  const std::string& run_id() const { return store_->run_id(); }
  std::string describe() const { return store_->describe(); }

 private:
  std::unique_ptr<store::ResultsStore> store_;
};

// Throws spec::SpecError (naming the property) for the first bad spec: a
// run whose properties are checked later (a bag) is recorded only if it can run.
void check_specs(const std::vector<engine::PropertySpec>& properties, bool dense);

// The properties and time model of a run as the store records them.
store::RunInfo run_info(const std::string& command, const std::vector<std::string>& inputs,
                        const std::vector<engine::PropertySpec>& properties, bool dense);

}  // namespace rvc::runtime
