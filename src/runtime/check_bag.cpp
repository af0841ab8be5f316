#include "runtime/check_bag.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <stdexcept>

#include "runtime/check_stream.hpp"
#include <filesystem>

#include "transport/rosbag2/bag_reader.hpp"

namespace rvc::runtime {

namespace {

std::string describe(const std::vector<transport::BagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) {
    if (t.messages == 0) continue;
    s += "\n  " + t.name + " (" + (t.type.empty() ? t.encoding : t.type) + ", " + std::to_string(t.messages) +
         " message" + (t.messages == 1 ? "" : "s") + ")";
  }
  return s;
}

// Whether a --msg-path folder holds the type's own definition: then it is
// taken from there, not from the bag (a user's definition corrects a bag
// whose recorded one is wrong or cut short, as some rosbag2 test bags are).
bool in_search_paths(const msg::TypeRegistry& registry, const std::string& type) {
  const size_t a = type.find('/'), b = type.rfind('/');
  if (a == std::string::npos) return false;
  const std::string pkg = type.substr(0, a), kind = a == b ? "msg" : type.substr(a + 1, b - a - 1),
                    name = type.substr(b + 1);
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const auto& dir : registry.search_paths())
    for (const char* ext : {".msg", ".idl"})
      for (const fs::path& p : {fs::path(dir) / pkg / kind / (name + ext), fs::path(dir) / "share" / pkg / kind / (name + ext),
                                fs::path(dir) / (name + ext)})
        if (fs::is_regular_file(p, ec)) return true;
  return false;
}

}  // namespace

BagInput select_bag_topic(const std::string& path, const std::string& topic, msg::TypeRegistry& registry) {
  const transport::BagSummary contents = transport::summarize_bag(path);
  size_t with_messages = 0;
  const transport::BagTopicInfo* only = nullptr;
  for (const auto& t : contents.topics)
    if (t.messages) {
      ++with_messages;
      only = &t;
    }
  if (with_messages == 0)
    throw std::invalid_argument(!contents.broken.empty()          ? contents.broken
                                : !contents.first_skipped.empty() ? contents.first_skipped
                                                                  : "bag '" + path + "' holds no messages");
  BagInput in;
  in.path = path;
  if (topic.empty()) {
    if (with_messages > 1)
      throw std::invalid_argument("bag '" + path + "' holds " + std::to_string(with_messages) +
                                  " topics: choose one with --topic" + describe(contents.topics));
    in.topic = only->name;
  } else {
    const transport::BagTopicInfo* t = contents.topic(topic);
    if (!t || t->messages == 0)
      throw std::invalid_argument("bag '" + path + "' has no " + (t ? "message on topic '" : "topic '") + topic +
                                  "'; its topics:" + describe(contents.topics));
    in.topic = topic;
  }
  const transport::BagTopicInfo& t = *contents.topic(in.topic);
  in.messages = t.messages;
  in.type_name = t.type;
  in.encoding = t.encoding;
  in.definition_encoding = t.definition.empty() ? "" : t.definition_encoding;
  in.definition = t.definition;
  if (t.encoding == "json") return in;  // JSON messages: the usual path
  if (t.encoding != "cdr")
    throw std::invalid_argument("topic '" + in.topic + "' of bag '" + path + "' is encoded as '" + t.encoding +
                                "': rvc reads ROS 2 CDR and JSON messages");
  if (t.type.empty())
    throw std::invalid_argument("topic '" + in.topic + "' of bag '" + path +
                                "' has no schema (no type): the bag does not say which type its CDR messages are");
  // A bag may name the type and hold no definition (sqlite3 bags before
  // Iron, some writers): then the type comes from --msg-path or the bundled
  // definitions, as does any type a definition uses but leaves out. A type
  // that --msg-path defines is taken from there.
  const bool defined = t.definition.find_first_not_of(" \t\r\n") != std::string::npos;
  const std::string source = "definition of " + in.topic + " in " + path;
  if (defined && !in_search_paths(registry, t.type)) {
    in.bag_definition = t.definition_encoding == "ros2msg" || t.definition_encoding == "ros2idl";
    if (t.definition_encoding == "ros2msg")
      registry.add_concatenated(t.type, t.definition, source);
    else if (t.definition_encoding == "ros2idl")  // types defined in .idl only (rosbag2 records them so)
      registry.add_concatenated_idl(t.definition, source);
    else if (!t.definition_encoding.empty())
      throw std::invalid_argument("topic '" + in.topic + "' of bag '" + path + "' has a '" + t.definition_encoding +
                                  "' definition: rvc reads ROS 2 definitions (ros2msg, ros2idl)");
  }
  in.type = &registry.resolve(t.type);
  return in;
}

void set_size_cap(BagInput& in, const PipelineOptions& options) {
  in.max_message_size = in.type ? options.max_typed_message_size : options.max_message_size;
}

void hint_bag_definition(const BagInput& in) {
  if (!in.bag_definition || !in.type) return;
  std::fprintf(stderr,
               "rvc: no message of %s decoded with the definition of %s that bag '%s' records: if that definition is "
               "wrong or cut short, give the type's .msg with --msg-path DIR (docs/bags.md)\n",
               in.topic.c_str(), in.type->full_name().c_str(), in.path.c_str());
}

Outcome check_bag(const std::vector<BagInput>& inputs, Feed& feed, VerdictOutputs& outputs, uint64_t& skipped,
                  const std::function<bool()>& stop, bool tick_at_end) {
  skipped = 0;
  return run_check(feed, outputs, [&](Outcome& outcome) {
    transport::BagReadOptions read;
    read.max_message_size = 0;
    for (const BagInput& in : inputs) {
      read.max_message_size = std::max(read.max_message_size, in.max_message_size);
      read.topics.push_back(in.topic);
    }
    std::unique_ptr<transport::BagReader> reader = transport::open_bag(inputs.at(0).path, read);
    transport::BagReader& bag = *reader;
    constexpr uint64_t kShown = 100;  // as the pipeline's errors: a bag of bad records does not flood stderr
    bag.on_skip([&](const std::string& reason) {
      if (skipped++ < kShown) std::fprintf(stderr, "rvc: bag '%s': %s\n", bag.path().c_str(), reason.c_str());
      outcome.rejected = true;
    });
    transport::BagMessage m;
    const bool copy_inputs = outputs.wants_inputs();
    double end_log = 0;  // the latest log time of any message: where the recording ends
    uint64_t end_log_ns = 0;  // the same, exact (mcap: outputs)
    double last_stamp = std::numeric_limits<double>::quiet_NaN(), stamp_log = 0;
    for (uint64_t n = 0;; ++n) {
      // Asked every 64 messages: a stop signal ends the bag within microseconds.
      if (stop && (n & 63) == 0 && stop()) {
        std::fprintf(stderr, "rvc: stopped by a signal after %llu messages: bag '%s' was not read to its end\n",
                     static_cast<unsigned long long>(n), bag.path().c_str());
        outcome.incomplete = true;
        break;
      }
      try {
        if (!bag.next(m)) break;
      } catch (const transport::BagError& e) {
        // A recording cut short: what came before the break was checked and
        // stands; the rest of the bag is bad input, not a failure of rvc.
        std::fprintf(stderr, "rvc: %s (the messages before it were checked)\n", e.what());
        outcome.rejected = true;
        break;
      }
      const double log_time = m.log_time * 1e-9;
      end_log = std::max(end_log, log_time);
      end_log_ns = std::max(end_log_ns, m.log_time);
      for (size_t i = 0; i < inputs.size(); ++i)
        if (m.topic == inputs[i].topic) {
          outputs.set_step_time(m.log_time);  // mcap: outputs place this step's verdicts at its log time
          feed.feed_logged(static_cast<uint32_t>(i), m.data, m.index, log_time);
          if (copy_inputs)  // after its step's verdicts: log times never go back in the file
            outputs.put_input({m.topic, inputs[i].type_name, inputs[i].encoding, inputs[i].definition_encoding,
                               inputs[i].definition, m.data, m.log_time});
          const double stamp = feed.last_stamp();
          if (!(stamp == last_stamp)) {  // the monitors took a message: stream time `stamp` at this log time
            last_stamp = stamp;
            stamp_log = log_time;
          }
        }
    }
    // Stopped by a signal, the recording did not end where reading did.
    if (tick_at_end && !outcome.incomplete && !std::isnan(last_stamp)) {
      outputs.set_step_time(end_log_ns);
      feed.end_of_input();  // what a synchronizer still holds, first: checked as the recording ends
      if (const double stamp = feed.last_stamp(); !(stamp == last_stamp)) {
        last_stamp = stamp;
        stamp_log = end_log;
      }
      feed.tick(last_stamp + std::max(0.0, end_log - stamp_log));
    }
    if (skipped > kShown)
      std::fprintf(stderr, "rvc: bag '%s': %llu more bad records were skipped and not shown\n", bag.path().c_str(),
                   static_cast<unsigned long long>(skipped - kShown));
  });
}

std::vector<SyncInput> select_bag_topics(const std::string& path, const std::vector<std::string>& topics,
                                         msg::TypeRegistry& registry, std::vector<BagInput>& bags) {
  std::vector<SyncInput> inputs;
  for (const auto& text : topics) {
    SyncInput in;
    std::string topic = text;
    const size_t eq = text.find('=');
    if (eq != std::string::npos && text[0] != '/') {
      in.name = text.substr(0, eq);
      topic = text.substr(eq + 1);
    } else {
      in.name = topic.substr(topic.find_last_of('/') + 1);
    }
    bags.push_back(select_bag_topic(path, topic, registry));
    in.uri = "bag:" + path + " " + topic;
    in.type = bags.back().type;
    inputs.push_back(std::move(in));
  }
  return inputs;
}

}  // namespace rvc::runtime
