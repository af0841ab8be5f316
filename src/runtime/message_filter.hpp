// The filter in front of the monitor (`rvc monitor --allow/--deny/--project`):
// which messages the properties see, by key or topic, and which of their
// fields. A Zenoh subscriber on a wildcard (vehicle/**) sees many keys; the
// filter keeps the ones wanted without a second subscription, and counts
// what it dropped (never silently: "filtered" in the counters).
#pragma once

#include <simdjson.h>

#include <string>
#include <string_view>
#include <vector>

namespace rvc::runtime {

// Key-expression matching as Zenoh users write it: '/'-separated chunks,
// '*' is exactly one chunk, '**' any number of chunks (also none).
bool key_matches(std::string_view pattern, std::string_view key);

struct FilterOptions {
  std::vector<std::string> allow;    // keys admitted (none given: all)
  std::vector<std::string> deny;     // keys refused (wins over allow)
  std::vector<std::string> project;  // fields kept (dotted paths); none given: all
};

class MessageFilter {
 public:
  // Throws std::invalid_argument for an empty pattern or field path.
  explicit MessageFilter(FilterOptions options);
  bool active() const { return !options_.allow.empty() || !options_.deny.empty() || projecting(); }
  bool projecting() const { return !options_.project.empty(); }

  bool admits(std::string_view key) const;
  // The payload's projected fields as one JSON object, in the order given
  // (a dotted path becomes nested objects; a missing field is left out, so
  // the monitor reports it as it would without the filter). False if the
  // payload is not a JSON object: the caller feeds it unchanged and the
  // monitor rejects it with its usual error.
  bool project(std::string_view payload, std::string& out);

 private:
  FilterOptions options_;
  std::vector<std::vector<std::string>> paths_;  // project, split at '.'
  simdjson::dom::parser parser_;
};

}  // namespace rvc::runtime
