#include "runtime/check_bag.hpp"

#include <cstdio>
#include <exception>
#include <stdexcept>

#include "runtime/check_stream.hpp"
#include "transport/mcap/mcap_bag.hpp"

namespace rvc::runtime {

namespace {

std::string describe(const std::map<std::string, transport::BagTopic>& topics) {
  std::string s;
  for (const auto& [name, t] : topics) {
    s += "\n  " + name + " (" + (t.schema_name.empty() ? t.message_encoding : t.schema_name) + ", " +
         std::to_string(t.messages) + " message" + (t.messages == 1 ? "" : "s") + ")";
  }
  return s;
}

}  // namespace

BagInput select_bag_topic(const std::string& path, const std::string& topic, msg::TypeRegistry& registry) {
  const transport::BagContents contents = transport::bag_topics(path);
  const auto& topics = contents.topics;
  if (topics.empty())
    throw std::invalid_argument(contents.broken.empty() ? "bag '" + path + "' holds no messages" : contents.broken);
  BagInput in;
  in.path = path;
  if (topic.empty()) {
    if (topics.size() > 1)
      throw std::invalid_argument("bag '" + path + "' holds " + std::to_string(topics.size()) +
                                  " topics: choose one with --topic" + describe(topics));
    in.topic = topics.begin()->first;
  } else {
    if (!topics.count(topic))
      throw std::invalid_argument("bag '" + path + "' has no topic '" + topic + "'; its topics:" + describe(topics));
    in.topic = topic;
  }
  const transport::BagTopic& t = topics.at(in.topic);
  in.messages = t.messages;
  if (t.message_encoding == "json") return in;  // JSON messages: the usual path
  if (t.message_encoding != "cdr")
    throw std::invalid_argument("topic '" + in.topic + "' of bag '" + path + "' is encoded as '" +
                                t.message_encoding + "': rvc reads ROS 2 CDR and JSON messages");
  if (t.schema_encoding != "ros2msg")
    throw std::invalid_argument("topic '" + in.topic + "' of bag '" + path + "' has a '" + t.schema_encoding +
                                "' schema: rvc reads ROS 2 .msg schemas (ros2msg)");
  registry.add_concatenated(t.schema_name, t.schema, "schema of " + in.topic + " in " + path);
  in.type = &registry.resolve(t.schema_name);
  return in;
}

Outcome check_bag(const BagInput& input, Pipeline& pipeline, VerdictOutputs& outputs) {
  return run_check(pipeline, outputs, [&](Outcome& outcome) {
    transport::McapBag bag(input.path);
    transport::McapMessage m;
    for (;;) {
      try {
        if (!bag.next(m)) break;
      } catch (const transport::McapError& e) {
        // A recording cut short: what came before the break was checked and
        // stands; the rest of the bag is bad input, not a failure of rvc.
        std::fprintf(stderr, "rvc: %s (the messages before it were checked)\n", e.what());
        outcome.rejected = true;
        break;
      }
      if (m.topic == input.topic) pipeline.feed(m.data, m.index);
    }
  });
}

}  // namespace rvc::runtime
