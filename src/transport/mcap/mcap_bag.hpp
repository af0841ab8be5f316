// A ROS 2 bag (MCAP file) read message by message, in file order, over the
// C ABI of rust/rvc-zenoh's MCAP reader (the `mcap` crate). Also finds which
// topics a bag holds and the message type of each from the bag's own schemas,
// so `rvc check bag.mcap` needs no --msg-path.
#pragma once

#include <cstdint>
#include <functional>
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
  uint64_t log_time = 0;   // ns
  uint64_t index = 0;      // 1-based over all topics
  uint16_t channel_id = 0;
};

class McapBag {
 public:
  explicit McapBag(const std::string& path);  // throws McapError
  ~McapBag();
  McapBag(const McapBag&) = delete;
  McapBag& operator=(const McapBag&) = delete;

  // False at the end; throws McapError when reading cannot go on (a record
  // whose length runs past the file: a recording cut short). A record that
  // is bad on its own (a chunk whose CRC does not match, a message on a
  // channel never defined) is skipped: `on_skip` gets the reason ("the chunk
  // at offset 4242: ...") and reading goes on.
  bool next(McapMessage& m);
  void on_skip(std::function<void(const std::string&)> f) { on_skip_ = std::move(f); }
  const std::string& path() const { return path_; }

  // Whether the file starts with MCAP's magic bytes.
  static bool looks_like_mcap(const std::string& path);

 private:
  std::string path_;
  rvc_mcap_reader* reader_ = nullptr;
  std::function<void(const std::string&)> on_skip_;
};

// One topic of a bag: its message count, channel (from its first message) and
// the span of its log times (ns).
struct BagTopic {
  uint64_t messages = 0;
  std::string message_encoding, schema_name, schema_encoding, schema;
  uint64_t first_time = 0, last_time = 0;
};

// Reads the whole bag once: every topic with its count and schema. A bag
// broken part-way (a recording cut short) gives the topics before the break
// and the reason in `broken`; records skipped on the way are left for the
// run that checks the bag to report.
struct BagContents {
  std::map<std::string, BagTopic> topics;
  std::string broken;
  std::string first_skipped;  // why the first record skipped was, if any
};
// `shown` names the bag in first_skipped (default: path). Throws McapError
// when the file cannot be opened as MCAP.
BagContents bag_topics(const std::string& path, const std::string& shown = "");

}  // namespace rvc::transport
