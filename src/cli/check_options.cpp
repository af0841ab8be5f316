#include "cli/check_options.hpp"

#include "cli/option_ranges.hpp"
#include "cli/option_rules.hpp"
#include "io/properties_file.hpp"

namespace rvc::cli {

void CheckOptions::add_to(CLI::App& app) {
  app.add_option("--spec,-s", specs, "A property in Rye syntax (repeatable; named p1, p2, ...)")->allow_extra_args(false);
  app.add_option("--properties,-p", properties_file, "YAML/JSON file of named properties")->check(CLI::ExistingFile);
  app.add_flag("--dense", dense, "Dense time: messages carry a time field; values hold until the next message");
  app.add_option("--origin", origin,
                 "Dense time: where the timeline starts. first (default): at the first message, nothing is said "
                 "about instants before it; zero: at time 0, with every field unseen until the first message "
                 "(Reelay's rule)")
      ->check(CLI::IsMember({"first", "zero"}))
      ->capture_default_str();
  app.add_flag("--all", all, "Report the verdict at every step, not only changes");
  app.add_flag("--robustness", robustness,
               "Report robustness values (Reelay's quantitative semantics: how far from changing the verdict; "
               "positive holds) instead of true/false; discrete and dense time, JSON and typed input, one input (not several "
               "synchronized ones) (docs/semantics.md)");
  app.add_flag("--explain", explain,
               "With each violation, say why: the sub-formulas and steps (dense: intervals) that made the verdict "
               "false, and for data references the value that decided");
  app.add_option("--max-data-values", max_data_values,
                 "Data references (exists[x]. {id: *x}): the most distinct values one variable may take; more stops "
                 "the run with an error (memory and time per message grow with them)")
      ->check(in_range(1, kMaxDataValues))
      ->capture_default_str();
  app.add_flag("--strict", strict, "Reject messages missing a field a property tests, or with wrong types");
  app.add_option("--time-field", time_field,
                 "Field holding the time in dense time: a path (header.stamp) to seconds or a Time {sec, nanosec} "
                 "(typed input without it: the message's header.stamp or stamp)")
      ->check(field_name())
      ->capture_default_str();
  max_message_size_option =
      app.add_option("--max-message-size", max_message_size,
                     "Longest accepted message in bytes (default: 1 MiB for JSON, 256 MiB for typed input: bags, --type)")
          ->check(in_range(1, kMaxMessageSize, "bytes"));
  app.add_option("--max-errors", max_reported, "Errors and warnings printed before going quiet (all are counted)")
      ->check(in_range(0, 1e9))
      ->capture_default_str();
  app.add_flag("--calls", calls,
               "The input is a ROS 2 service's events (<service>/_service_event, pkg/srv/Name_Event): pair request "
               "and response by info.client_gid + info.sequence_number and check one message per call, as `rvc calls` "
               "writes it: {time, request_time, answered, latency, sequence_number, request, response} "
               "(docs/services.md)");
  app.add_option("--service-timeout", service_timeout,
                                 "With --calls: seconds after its request a call with no response is made "
                                 "answered:false (by the events' stamps, or the monitor's clock)")
                      ->check(above_up_to(0, kMaxSeconds, "seconds"))
                      ->capture_default_str();
  app.add_flag("--parse-only", parse_only, "Decode messages but run no monitor (the benchmark's floor)")
      ->group("");  // hidden: for bench/, not for users
  app.add_flag("--no-layouts", no_layouts, "Parse every message with simdjson (no layout fast path)")
      ->group("");  // hidden: for bench/ and for comparing the two paths
  app.add_flag("--plain-eval", plain_eval,
               "Evaluate every field test and step every operator at every message (no threshold index, no "
               "change-driven stepping)")
      ->group("");  // hidden: for bench/ and the differential tests of the two paths
}

std::vector<engine::PropertySpec> CheckOptions::properties() const {
  std::vector<engine::PropertySpec> out;
  for (size_t i = 0; i < specs.size(); ++i) out.push_back({"p" + std::to_string(i + 1), specs[i]});
  if (!properties_file.empty()) {
    auto more = io::load_properties(properties_file);
    const size_t from_specs = out.size();  // the file's own names are unique already (load_properties)
    for (auto& p : more) {
      for (size_t i = 0; i < from_specs; ++i)  // not against the file's: 10,000 properties would be 10^8 comparisons
        if (out[i].name == p.name)
          throw io::PropertiesError(properties_file + ": property name '" + p.name + "' is also used by --spec");
      out.push_back(std::move(p));
    }
  }
  if (out.empty()) throw CLI::ValidationError("give a property with --spec or --properties");
  return out;
}

PipelineOptions CheckOptions::pipeline_options() const {
  PipelineOptions o;
  o.model = dense ? engine::TimeModel::Dense : engine::TimeModel::Discrete;
  o.emit_all = all;
  o.strict = strict;
  o.time_field = time_field;
  o.max_reported = max_reported;
  o.parse_only = parse_only;
  o.layouts = !no_layouts;
  o.incremental = !plain_eval;
  o.robustness = robustness;
  o.explain = explain;
  o.max_data_values = max_data_values;
  o.max_message_size = max_message_size;
  o.origin = origin == "zero" ? runtime::Origin::Zero : runtime::Origin::First;
  // Given, it is the cap for every input; else typed input keeps its own
  // (a CDR decode copies nothing it does not test: camera frames pass).
  if (max_message_size_option && max_message_size_option->count()) o.max_typed_message_size = max_message_size;
  return o;
}

}  // namespace rvc::cli
