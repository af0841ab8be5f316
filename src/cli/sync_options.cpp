#include "cli/sync_options.hpp"

#include "cli/option_ranges.hpp"

#include <cctype>
#include <cmath>
#include <stdexcept>

namespace rvc::cli {
namespace {

size_t index_of(const std::vector<runtime::SyncInput>& inputs, const std::string& name, const char* flag) {
  for (size_t i = 0; i < inputs.size(); ++i)
    if (inputs[i].name == name) return i;
  std::string names;
  for (const auto& in : inputs) names += (names.empty() ? "" : ", ") + in.name;
  throw std::invalid_argument(std::string(flag) + " names input '" + name + "', but the inputs are: " + names);
}

// NAME=VALUE of a per-input flag.
std::pair<std::string, std::string> named_value(const std::string& text, const char* flag) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 == text.size())
    throw std::invalid_argument(std::string(flag) + " '" + text + "': expected NAME=VALUE (NAME: an input's name)");
  return {text.substr(0, eq), text.substr(eq + 1)};
}

}  // namespace

void SyncFlags::add_to(CLI::App& app) {
  app.add_option("--stamp", stamps,
                 "Several inputs: NAME=PATH reads input NAME's stamp from a field (a Time message or seconds), "
                 "NAME=arrival uses the time it arrives (default: typed header.stamp or stamp, else arrival; JSON: "
                 "--time-field)");
  app.add_option("--sync", policy,
                 "Several inputs: merge (each message is an event, the others' fields hold), approximate "
                 "(message_filters ApproximateTime), exact (equal stamps), latest (a set per message of the "
                 "fastest input)")
      ->check(CLI::IsMember({"merge", "approximate", "exact", "latest"}))
      ->capture_default_str();
  app.add_option("--sync-queue", queue_size, "approximate/exact: messages kept per input (message_filters queue size)")
      ->check(in_range(1, kMaxSyncQueue))
      ->capture_default_str();
  app.add_option("--max-interval", max_interval, "approximate: widest set in seconds (newest - oldest stamp)")
      ->check(in_range(0, HUGE_VAL, "seconds"));
  app.add_option("--age-penalty", age_penalty, "approximate: message_filters' age penalty")
      ->check(in_range(0, 1e9))
      ->capture_default_str();
  app.add_option("--lower-bound", lower_bounds,
                 "approximate: NAME=SECONDS, the least time between two messages of input NAME (sets go out sooner)");
  app.add_option("--max-delay", max_delay,
                 "merge: least seconds a message waits for earlier-stamped ones from other inputs (the wait grows to twice "
                 "the lateness seen, up to 60 s or this); later ones are late")
      ->check(in_range(0, kMaxDelaySeconds, "seconds"))
      ->capture_default_str();
  app.add_option("--late", late,
                 "merge: what becomes of a message stamped before an event already checked: drop it (counted, "
                 "warned, exit 3) or process it as the next event")
      ->check(CLI::IsMember({"drop", "process"}))
      ->capture_default_str();
  app.add_option("--pivot", pivot, "latest: the input whose messages make sets (default: the fastest)");
  app.add_option("--dead-after", dead_after,
                 "Warn about an input silent for S seconds while the others deliver (0: never)")
      ->check(in_range(0, kMaxSeconds, "seconds"))
      ->capture_default_str();
}

bool SyncFlags::split_named(const std::string& text, std::string& name, std::string& uri) {
  const size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0) return false;
  for (size_t i = 0; i < eq; ++i) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (!(std::isalnum(c) || c == '_')) return false;  // "file:a=b", "./x=y": a URI
  }
  name = text.substr(0, eq);
  uri = text.substr(eq + 1);
  return true;
}

bool SyncFlags::named(const std::vector<std::string>& inputs) {
  std::string name, uri;
  for (const auto& i : inputs)
    if (split_named(i, name, uri)) return true;
  return inputs.size() > 1;
}

std::vector<runtime::SyncInput> SyncFlags::resolve(const std::vector<std::string>& inputs, const CLI::App& app,
                                                   const CLI::Option* input_option, TypeOptions& typed,
                                                   const transport::TransportOptions& transports,
                                                   std::vector<transport::TransportOptions>& per_input) const {
  std::vector<runtime::SyncInput> out;
  for (const auto& text : inputs) {
    runtime::SyncInput in;
    if (!split_named(text, in.name, in.uri))
      throw std::invalid_argument("with several inputs each is NAME=URI (properties test {NAME.field}): '" + text +
                                  "'");
    if (in.uri.empty()) throw std::invalid_argument("--input " + text + ": no URI after '" + in.name + "='");
    out.push_back(std::move(in));
  }
  // Types: each --type applies to the --input before it, or names its input.
  std::vector<std::string> type_names(out.size());
  const auto& type_values = typed.type_option->results();
  size_t inputs_seen = 0, types_seen = 0;
  for (const CLI::Option* opt : app.parse_order()) {
    if (opt == input_option) {
      ++inputs_seen;
    } else if (opt == typed.type_option && types_seen < type_values.size()) {
      const std::string& value = type_values[types_seen++];
      std::string name, type;
      if (split_named(value, name, type)) {
        type_names[index_of(out, name, "--type")] = type;
      } else if (inputs_seen == 0) {
        throw std::invalid_argument("--type " + value + " comes before any --input: put it after the input it is for");
      } else {
        type_names[inputs_seen - 1] = value;
      }
    }
  }
  for (const auto& p : typed.msg_paths) typed.registry.add_search_path(p);
  per_input.assign(out.size(), transports);
  for (size_t i = 0; i < out.size(); ++i) {
    if (type_names[i].empty() && transport::scheme_of(out[i].uri) == "rmw_zenoh") {
      TypeOptions from_graph;  // rmw_zenoh: the type its publishers announce
      from_graph.infer_from_graph(out[i].uri, transports);
      type_names[i] = from_graph.type;
      typed.graph_session = from_graph.graph_session;  // the session stays open for the inputs
    }
    if (type_names[i].empty()) continue;
    if (!TypeOptions::typed_scheme(out[i].uri))
      throw std::invalid_argument("input '" + out[i].name + "': --type reads dds: topics or zenoh: keys, not " +
                                  out[i].uri);
    out[i].type = &typed.registry.resolve(type_names[i]);
#ifdef RVC_HAVE_DDS
    per_input[i].dds.ros_type = out[i].type;
#endif
#ifdef RVC_HAVE_ZENOH
    per_input[i].rmw_zenoh.ros_type = type_names[i];
#endif
  }
  apply_stamps(out);
  return out;
}

void SyncFlags::apply_stamps(std::vector<runtime::SyncInput>& inputs) const {
  for (const auto& s : stamps) {
    auto [name, path] = named_value(s, "--stamp");
    inputs[index_of(inputs, name, "--stamp")].stamp = path;
  }
}

SyncFlags::Sources SyncFlags::open_sources(const std::vector<runtime::SyncInput>& inputs,
                                           const std::vector<transport::TransportOptions>& per_input) {
  Sources s;
  for (size_t i = 0; i < inputs.size(); ++i) {
    s.owned.push_back(transport::open_source(inputs[i].uri, per_input[i]));
    s.list.push_back(s.owned.back().get());
  }
  return s;
}

std::string SyncFlags::joined_names(const std::vector<runtime::SyncInput>& inputs) {
  std::string s;
  for (const auto& in : inputs) s += (s.empty() ? "" : ",") + in.name;
  return s;
}

runtime::SyncOptions SyncFlags::options(const std::vector<runtime::SyncInput>& inputs) const {
  runtime::SyncOptions o;
  o.policy = sync::policy_from_string(policy);
  o.dead_after = dead_after;
  sync::PolicyOptions& p = o.policy_options;
  p.inputs = inputs.size();
  p.queue_size = queue_size;
  p.max_interval = max_interval;
  p.age_penalty = age_penalty;
  p.max_delay = max_delay;
  // Live stamps jitter: the wait adapts to the lateness seen (docs/sync.md).
  p.adaptive_limit = kAdaptiveDelayLimit;
  p.process_late = late == "process";
  // Files (all of them: a mix with topics is refused) are read in stamp order.
  o.ordered = !inputs.empty();
  for (const auto& in : inputs) o.ordered = o.ordered && transport::scheme_of(in.uri) == "file";
  // Live inputs and bags: a stamp waits until every input has passed it (an
  // input silent for --dead-after seconds, or ended, is no longer waited for).
  p.wait_for_inputs = !o.ordered;
  p.max_held = static_cast<size_t>(kMaxMergeHeld);
  if (!pivot.empty()) p.pivot = static_cast<int>(index_of(inputs, pivot, "--pivot"));
  if (!lower_bounds.empty()) {
    p.inter_message_lower_bound.assign(inputs.size(), 0);
    for (const auto& b : lower_bounds) {
      auto [name, seconds] = named_value(b, "--lower-bound");
      const size_t i = index_of(inputs, name, "--lower-bound");
      try {
        p.inter_message_lower_bound[i] = std::stod(seconds);
      } catch (const std::logic_error&) {
        throw std::invalid_argument("--lower-bound " + b + ": '" + seconds + "' is not a number of seconds");
      }
    }
  }
  return o;
}

}  // namespace rvc::cli
