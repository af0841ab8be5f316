// Checking a ROS 2 bag (MCAP): the messages of one topic, in the order the bag
// stores them, through the same Pipeline and VerdictOutputs as a JSON-lines
// file. The topic's type comes from the bag's own schema (a ROS 2 bag
// carries the .msg text of every type it holds), so no --msg-path is needed.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "msg/type_registry.hpp"
#include "runtime/exit_status.hpp"
#include "runtime/pipeline.hpp"
#include "runtime/synced_pipeline.hpp"
#include "runtime/verdict_outputs.hpp"

namespace rvc::runtime {

struct BagInput {
  std::string path;
  std::string topic;                     // the topic checked
  const msg::MessageType* type = nullptr;  // CDR samples of this type; null: JSON messages
  uint64_t messages = 0;                 // of that topic
  bool bag_definition = false;           // its definition came from the bag (not --msg-path or bundled)
  // The run's cap on one message of this topic (--max-message-size): a
  // compressed message is decompressed only up to it (set_size_cap).
  size_t max_message_size = size_t{256} << 20;
  // As the bag records the topic (copied with its messages by mcap:PATH?inputs=1).
  std::string type_name, encoding, definition_encoding, definition;
};

// The cap of `options` that applies to the topic's messages (typed or JSON).
void set_size_cap(BagInput& in, const PipelineOptions& options);

// When no sample of a topic decoded and its definition came from the bag:
// the hint that the recorded definition may be wrong (some rosbag2 bags
// record stand-ins), printed once on stderr.
void hint_bag_definition(const BagInput& in);

// Picks the topic to check: `topic` if given (it must be in the bag), else
// the bag's only topic. Registers its schema in `registry` and resolves the
// type. Throws std::invalid_argument naming the bag's topics (with their
// types and counts) when there is no single choice, and for encodings rvc
// cannot read; transport::McapError for a file that is no bag.
BagInput select_bag_topic(const std::string& path, const std::string& topic, msg::TypeRegistry& registry);

// Feeds every message of the chosen topics to the feed in the bag's order,
// topic i as input i, its log time as its arrival (positions are the
// messages' 1-based indexes in the bag, over all topics). One topic: a
// Pipeline; several: a SyncedPipeline. Like check_stream, never throws for a
// failure while running: the outcome says so.
//
// A bad record of the bag (a chunk whose CRC does not match, a message on a
// channel never defined, ...) is reported with its offset, skipped and
// counted in `skipped` (the run's rejected input: exit 3 unless a property
// is violated); the messages around it are still checked.
// `stop` (may be empty) is asked between messages: when it says so (a stop
// signal), reading ends there, what was read is checked, and the outcome is
// incomplete (the bag was not read to its end).
//
// `tick_at_end` (dense time on the bag's own clock): after the last message,
// a tick at the recording's end, so what falls after the last message of the
// checked topics but before the recording ends is reported. The recording's
// end is the latest log time of any message in the bag (what the MCAP
// statistics record call message_end_time); in stream time (the messages'
// stamps) it is the last stamp the monitors took plus the log time that
// passed after its message.
Outcome check_bag(const std::vector<BagInput>& inputs, Feed& feed, VerdictOutputs& outputs, uint64_t& skipped,
                  const std::function<bool()>& stop = {}, bool tick_at_end = false);

// Several topics of a bag: "NAME=TOPIC" or "TOPIC" (named by its last part,
// "/vehicle/status/gear_status" -> gear_status). The inputs to synchronize,
// their types from the bag; `bags` gets what check_bag needs.
std::vector<SyncInput> select_bag_topics(const std::string& path, const std::vector<std::string>& topics,
                                         msg::TypeRegistry& registry, std::vector<BagInput>& bags);

}  // namespace rvc::runtime
