#include "transport/mcap/mcap_bag.hpp"

#include <algorithm>

#include <cstring>
#include <fstream>
#include <vector>

extern "C" const char* rvc_zenoh_last_error(void);

namespace rvc::transport {

McapBag::McapBag(const std::string& path) : path_(path) {
  if (rvc_mcap_open(path.c_str(), &reader_) != 0) throw McapError("bag '" + path + "': " + rvc_zenoh_last_error());
}

McapBag::~McapBag() { rvc_mcap_close(reader_); }

bool McapBag::next(McapMessage& m) {
  rvc_mcap_message raw{};
  int rc;
  while ((rc = rvc_mcap_next(reader_, &raw)) == RVC_MCAP_SKIPPED)
    if (on_skip_) on_skip_(rvc_zenoh_last_error());
  if (rc < 0) throw McapError("bag '" + path_ + "': " + rvc_zenoh_last_error());
  if (rc == 0) return false;
  auto text = [](const char* s) { return std::string_view(s, std::strlen(s)); };
  m.topic = text(raw.topic);
  m.message_encoding = text(raw.message_encoding);
  m.schema_name = text(raw.schema_name);
  m.schema_encoding = text(raw.schema_encoding);
  m.schema = std::string_view(reinterpret_cast<const char*>(raw.schema_data), raw.schema_len);
  m.data = std::string_view(reinterpret_cast<const char*>(raw.data), raw.len);
  m.log_time = raw.log_time;
  m.index = raw.index;
  m.channel_id = raw.channel_id;
  return true;
}

bool McapBag::looks_like_mcap(const std::string& path) {
  static constexpr char kMagic[] = "\x89MCAP0\r\n";
  std::ifstream in(path, std::ios::binary);
  char head[8] = {};
  return in.read(head, 8) && std::memcmp(head, kMagic, 8) == 0;
}

BagContents bag_topics(const std::string& path, const std::string& shown) {
  BagContents contents;
  auto& topics = contents.topics;
  McapBag bag(path);
  const std::string& name = shown.empty() ? path : shown;
  bag.on_skip([&](const std::string& reason) {
    if (contents.first_skipped.empty()) contents.first_skipped = "bag '" + name + "': " + reason;
  });
  McapMessage m;
  // Each channel's topic, found once: a bag of many channels costs no more
  // per message than a bag of one.
  std::vector<BagTopic*> by_channel(65536, nullptr);
  for (;;) {
    try {
      if (!bag.next(m)) break;
    } catch (const McapError& e) {
      contents.broken = e.what();
      break;
    }
    BagTopic*& slot = by_channel[m.channel_id];
    if (!slot) slot = &topics[std::string(m.topic)];
    BagTopic& t = *slot;
    if (t.messages++ == 0) {
      t.message_encoding = m.message_encoding;
      t.schema_name = m.schema_name;
      t.schema_encoding = m.schema_encoding;
      t.schema = m.schema;
      t.first_time = t.last_time = m.log_time;
    }
    t.first_time = std::min(t.first_time, m.log_time);
    t.last_time = std::max(t.last_time, m.log_time);
  }
  return contents;
}

}  // namespace rvc::transport
