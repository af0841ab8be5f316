// `rvc hz` topics and their topic_state_monitor parameters, from the command
// line and/or a YAML file (--config):
//
//   warn_rate: 8          # defaults for every topic (optional)
//   error_rate: 5
//   timeout: 1.0
//   window_size: 10
//   topics:
//     - topic: dds:/chatter        # an endpoint URI, as on the command line
//       warn_rate: 9               # per topic, over the defaults
//       type: std_msgs/msg/Header  # optional: else --type, else JSON payloads
//       stamp_field: header.stamp  # optional: latency from this field; none: no latency
//
// Precedence, lowest first: built-in defaults, the file's top-level values,
// command-line flags, a topic's own entry.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "runtime/topic_rate.hpp"

namespace rvc::cli {

struct HzTopicConfig {
  std::string uri;
  runtime::RateThresholds thresholds;
  std::string type;         // ROS 2 type; empty: the --type given (or JSON)
  std::string stamp_field;  // empty: automatic; "none": no latency
};

// Parameters the command line set (nullopt: not given there).
struct HzFlagOverrides {
  std::optional<double> warn_rate, error_rate, timeout;
  std::optional<size_t> window_size;
};

// The topics to watch: the file's, then the command line's URIs that the
// file does not list. Throws std::invalid_argument naming the file, line and
// key for a bad file (unknown key, a value that is no number >= 0, a window
// below 2, a topic twice), and for no topic at all.
std::vector<HzTopicConfig> hz_topics(const std::string& config_path, const std::vector<std::string>& uris,
                                     const HzFlagOverrides& flags);

}  // namespace rvc::cli
