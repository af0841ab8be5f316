// Options shared by `rvc check` and `rvc monitor`: what to check and how.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "runtime/pipeline.hpp"
#include "engine/checker.hpp"

namespace rvc::cli {

using runtime::PipelineOptions;

struct CheckOptions {
  std::vector<std::string> specs;
  std::string properties_file;
  bool dense = false;
  std::string origin = "first";  // --origin first|zero (dense time)
  bool all = false;
  bool strict = false;
  std::string time_field = "time";
  size_t max_message_size = 1 << 20;  // JSON; typed input: PipelineOptions' own default unless given
  CLI::Option* max_message_size_option = nullptr;
  size_t max_reported = 100;
  bool parse_only = false;
  bool no_layouts = false;
  bool plain_eval = false;
  bool robustness = false;
  bool explain = false;
  uint32_t max_data_values = 100000;
  bool calls = false;           // --calls: the input is a service's events, checked as calls (docs/services.md)
  double service_timeout = 1;   // --service-timeout: a request unanswered this long is a call answered:false

  void add_to(CLI::App& app);
  // The properties from --spec (named p1, p2, ...) and --properties.
  std::vector<engine::PropertySpec> properties() const;
  PipelineOptions pipeline_options() const;
  // --calls: the timeout (0 without --calls).
  double calls_timeout() const { return calls ? service_timeout : 0; }
};

}  // namespace rvc::cli
