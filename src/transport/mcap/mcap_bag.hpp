// A ROS 2 bag (MCAP file) read message by message, in file order, over the
// C ABI of rust/rvc-zenoh's MCAP reader (the `mcap` crate). Also finds which
// topics a bag holds and the message type of each from the bag's own schemas,
// so `rvc check bag.mcap` needs no --msg-path.
#pragma once

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <string_view>

#include "transport/mcap/rvc_mcap.h"

namespace rvc::transport {

// A bag that cannot be opened or read: names the file and what is wrong.
class McapError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct McapMessage {
  std::string_view topic, message_encoding, schema_name, schema_encoding, schema, data;
  uint64_t log_time = 0;  // ns
  uint64_t index = 0;     // 1-based over all topics
};

class McapBag {
 public:
  explicit McapBag(const std::string& path);  // throws McapError
  ~McapBag();
  McapBag(const McapBag&) = delete;
  McapBag& operator=(const McapBag&) = delete;

  // False at the end; throws McapError for a broken record.
  bool next(McapMessage& m);
  const std::string& path() const { return path_; }

  // Whether the file starts with MCAP's magic bytes.
  static bool looks_like_mcap(const std::string& path);

 private:
  std::string path_;
  rvc_mcap_reader* reader_ = nullptr;
};

// One topic of a bag: its message count and channel (from its first message).
struct BagTopic {
  uint64_t messages = 0;
  std::string message_encoding, schema_name, schema_encoding, schema;
};

// Reads the whole bag once: every topic with its count and schema. A bag
// broken part-way (a recording cut short) gives the topics before the break
// and the reason in `broken`.
struct BagContents {
  std::map<std::string, BagTopic> topics;
  std::string broken;
};
BagContents bag_topics(const std::string& path);

}  // namespace rvc::transport
