// libFuzzer harness: a ROS 2 bag (MCAP) read through the C ABI of the Rust
// reader (rust/rvc-zenoh/src/mcap_reader.rs) as `rvc check bag.mcap` reads
// it: the topics pass (transport::bag_topics), then every message, then each
// topic's ros2msg schema and CDR samples (registry, cdr_to_json).
//
// Run with a malloc limit (scripts/fuzz.sh reads tests/fuzz/fuzz_mcap.flags):
// an allocation sized by a length the file declares rather than by the bytes
// it holds is a finding, as is any crash or sanitizer report. Oracles: the
// bag reads the same twice (same messages, same skipped records, same end),
// and the topics pass counts exactly the messages the read pass returns.
//
// The Rust library is built by cargo in release mode, without libFuzzer's
// coverage instrumentation: mutations of the seed bags are guided only by
// the C++ side's coverage (schemas, samples).
#include <sys/mman.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "io/cdr_codec.hpp"
#include "msg/type_registry.hpp"
#include "transport/mcap/mcap_bag.hpp"

namespace {

struct Pass {
  std::vector<std::string> events;  // "m <topic> <index> <size>" or "s <reason>", then "end ..."
  std::map<std::string, uint64_t> per_topic;
};

Pass read_all(const std::string& path) {
  Pass p;
  try {
    rvc::transport::McapBag bag(path);
    bag.on_skip([&](const std::string& reason) { p.events.push_back("s " + reason); });
    rvc::transport::McapMessage m;
    for (;;) {
      try {
        if (!bag.next(m)) break;
      } catch (const rvc::transport::McapError& e) {
        p.events.push_back(std::string("end ") + e.what());
        return p;
      }
      p.events.push_back("m " + std::string(m.topic) + " " + std::to_string(m.index) + " " +
                         std::to_string(m.data.size()));
      ++p.per_topic[std::string(m.topic)];
    }
    p.events.push_back("end");
  } catch (const rvc::transport::McapError& e) {
    p.events.push_back(std::string("open ") + e.what());
  }
  return p;
}

void check_samples(const std::string& path, const rvc::transport::BagContents& contents) {
  rvc::msg::TypeRegistry registry;
  std::map<std::string, const rvc::msg::MessageType*> types;
  for (const auto& [topic, t] : contents.topics) {
    if (t.message_encoding != "cdr" || t.schema_encoding != "ros2msg") continue;
    try {
      registry.add_concatenated(t.schema_name, t.schema, "fuzz");
      types[topic] = &registry.resolve(t.schema_name);
    } catch (const std::exception&) {  // MsgError, or a name the registry refuses
    }
  }
  if (types.empty()) return;
  rvc::transport::McapBag bag(path);
  rvc::transport::McapMessage m;
  std::string json;
  try {
    while (bag.next(m)) {
      auto it = types.find(std::string(m.topic));
      if (it == types.end()) continue;
      rvc::io::CdrError error;
      json.clear();
      (void)rvc::io::cdr_to_json(*it->second, m.data, json, error);
    }
  } catch (const rvc::transport::McapError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The reader maps a file, as rvc does: the input becomes one in memory.
  const int fd = memfd_create("fuzz.mcap", 0);
  if (fd < 0) __builtin_trap();
  for (size_t done = 0; done < size;) {
    const ssize_t n = write(fd, data + done, size - done);
    if (n <= 0) __builtin_trap();
    done += static_cast<size_t>(n);
  }
  const std::string path = "/proc/self/fd/" + std::to_string(fd);
  const Pass first = read_all(path);
  const Pass second = read_all(path);
  if (first.events != second.events) __builtin_trap();  // reading is deterministic
  try {
    const rvc::transport::BagContents contents = rvc::transport::bag_topics(path);
    uint64_t listed = 0;
    for (const auto& [topic, t] : contents.topics) {
      auto it = first.per_topic.find(topic);
      if (it == first.per_topic.end() || it->second != t.messages) __builtin_trap();
      listed += t.messages;
    }
    uint64_t read = 0;
    for (const auto& [topic, n] : first.per_topic) read += n;
    if (listed != read) __builtin_trap();
    check_samples(path, contents);
  } catch (const rvc::transport::McapError&) {  // not an MCAP file: the read passes said so too
    if (first.events.empty() || first.events.back().rfind("open ", 0) != 0) __builtin_trap();
  }
  close(fd);
  return 0;
}
