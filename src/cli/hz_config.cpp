#include "cli/hz_config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>
#include <stdexcept>

namespace rvc::cli {
namespace {

const std::set<std::string> kThresholdKeys = {"warn_rate", "error_rate", "timeout", "window_size"};

struct YamlFile {
  std::string path;
  std::string where(const YAML::Node& n) const {
    return path + ":" + std::to_string(n.Mark().line + 1) + ":" + std::to_string(n.Mark().column + 1);
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& what) const {
    throw std::invalid_argument(where(n) + ": " + what);
  }
  std::string text(const YAML::Node& n, const std::string& key) const {
    if (!n.IsScalar()) fail(n, key + " must be a string");
    return n.as<std::string>();
  }
  double number(const YAML::Node& n, const std::string& key) const {
    double v = -1;
    // The command line's bounds: rates to 1e9 Hz, a timeout to a week.
    const double max = key == "timeout" ? 86400.0 * 7 : 1e9;
    if (!n.IsScalar() || !YAML::convert<double>::decode(n, v) || !std::isfinite(v) || v < 0 || v > max)
      fail(n, key + " must be a number from 0 (off) to " + (key == "timeout" ? std::string("604800") : std::string("1e9")) + ", got '" + (n.IsScalar() ? n.Scalar() : std::string("a list or map")) +
                  "'");
    return v;
  }
  // One threshold key of a map (top level or a topic's entry) into `t`.
  void threshold(const std::string& key, const YAML::Node& value, runtime::RateThresholds& t) const {
    if (key == "warn_rate") t.warn_rate = number(value, key);
    else if (key == "error_rate") t.error_rate = number(value, key);
    else if (key == "timeout") t.timeout = number(value, key);
    else {
      const double w = number(value, key);
      if (w < 2 || w != std::floor(w) || w > 1e7)
        fail(value, "window_size must be a whole number of arrivals from 2 to 10000000, got '" + value.Scalar() + "'");
      t.window_size = static_cast<size_t>(w);
    }
  }
};

void apply_flags(const HzFlagOverrides& flags, runtime::RateThresholds& t) {
  if (flags.warn_rate) t.warn_rate = *flags.warn_rate;
  if (flags.error_rate) t.error_rate = *flags.error_rate;
  if (flags.timeout) t.timeout = *flags.timeout;
  if (flags.window_size) t.window_size = *flags.window_size;
}

}  // namespace

std::vector<HzTopicConfig> hz_topics(const std::string& config_path, const std::vector<std::string>& uris,
                                     const HzFlagOverrides& flags) {
  runtime::RateThresholds defaults;
  std::vector<HzTopicConfig> out;
  std::set<std::string> seen;
  if (!config_path.empty()) {
    const YamlFile file{config_path};
    YAML::Node root;
    try {
      root = YAML::LoadFile(config_path);
    } catch (const YAML::BadFile&) {
      throw std::invalid_argument(config_path + ": cannot open the rvc hz configuration");
    } catch (const YAML::ParserException& e) {
      throw std::invalid_argument(config_path + ":" + std::to_string(e.mark.line + 1) + ":" +
                                  std::to_string(e.mark.column + 1) + ": " + e.msg);
    }
    if (!root.IsMap()) throw std::invalid_argument(config_path + ": expected a map with 'topics:' (and optional defaults)");
    YAML::Node topics;
    for (const auto& kv : root) {
      const std::string key = kv.first.as<std::string>();
      if (key == "topics") topics = kv.second;
      else if (kThresholdKeys.count(key)) file.threshold(key, kv.second, defaults);
      else
        file.fail(kv.first, "unknown key '" + key + "' (expected topics, warn_rate, error_rate, timeout, window_size)");
    }
    apply_flags(flags, defaults);
    if (topics && !topics.IsNull()) {
      if (!topics.IsSequence()) file.fail(topics, "topics must be a list of {topic: URI, ...}");
      for (const auto& entry : topics) {
        HzTopicConfig t;
        t.thresholds = defaults;
        if (entry.IsScalar()) {
          t.uri = entry.as<std::string>();
        } else if (entry.IsMap()) {
          for (const auto& kv : entry) {
            const std::string key = kv.first.as<std::string>();
            if (key == "topic" || key == "uri") t.uri = file.text(kv.second, key);
            else if (key == "type") t.type = file.text(kv.second, key);
            else if (key == "stamp_field") t.stamp_field = file.text(kv.second, key);
            else if (kThresholdKeys.count(key)) file.threshold(key, kv.second, t.thresholds);
            else
              file.fail(kv.first, "unknown key '" + key +
                                      "' in a topic (expected topic, type, stamp_field, warn_rate, error_rate, "
                                      "timeout, window_size)");
          }
        } else {
          file.fail(entry, "a topic is a URI or a map {topic: URI, ...}");
        }
        if (t.uri.empty()) file.fail(entry, "a topic without 'topic: URI'");
        if (!seen.insert(t.uri).second) file.fail(entry, "topic '" + t.uri + "' is listed twice");
        out.push_back(std::move(t));
      }
    }
  } else {
    apply_flags(flags, defaults);
  }
  for (const auto& uri : uris) {
    if (seen.count(uri)) continue;  // the file's entry, with its own parameters
    seen.insert(uri);
    HzTopicConfig t;
    t.uri = uri;
    t.thresholds = defaults;
    out.push_back(std::move(t));
  }
  if (out.empty()) throw std::invalid_argument("no topic to watch: give endpoint URIs or --config with topics:");
  return out;
}

}  // namespace rvc::cli
