// Writing an MCAP file (https://mcap.dev/spec), without chunks: records are
// appended as they come, so a file cut short (a crash) still holds every
// message written before the cut, and a reader that scans linearly gets them.
//
//   magic, Header(profile, library), data: Schema / Channel records (each before
//   its channel's first message) and Message records, DataEnd (with the CRC of
//   everything before it), summary (every
//   Schema and Channel again, Statistics), Summary Offset records, Footer, magic
//
// close() writes everything after the data section; until then the file has no
// footer. Written from the specification, in C++ (the reader in rust/rvc-zenoh
// is Foxglove's crate; this writer needs no Rust and is built in every preset).
#pragma once

#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace rvc::transport::mcap {

class McapWriter {
 public:
  // Writes the magic and the Header. `file` stays owned by the caller.
  McapWriter(std::FILE* file, std::string_view profile, std::string_view library);

  // Registers a schema (Schema record, written now); returns its id (1, 2, ...).
  uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  // Registers a channel (Channel record, written now); schema_id 0 = none.
  uint16_t add_channel(uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                       const std::map<std::string, std::string>& metadata = {});
  // One Message record. Times in nanoseconds.
  void write_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
                     std::string_view data);
  // DataEnd, the summary, its offsets, the Footer and the closing magic. Idempotent.
  void close();
  bool closed() const { return closed_; }
  // Throws std::runtime_error when a write failed (errno's text), from any call above.

  uint64_t message_count() const { return message_count_; }

 private:
  struct Schema {
    uint16_t id;
    std::string name, encoding, data;
  };
  struct Channel {
    uint16_t id, schema_id;
    std::string topic, message_encoding;
    std::map<std::string, std::string> metadata;
  };
  static void schema_record(std::string& out, const Schema& s);
  static void channel_record(std::string& out, const Channel& c);
  void emit(std::string_view bytes);  // to the file, counting the offset

  std::FILE* file_;
  uint64_t offset_ = 0;
  uint32_t data_crc_ = 0;  // CRC-32 of every byte written before DataEnd
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  std::map<uint16_t, uint64_t> per_channel_;
  uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0;
  std::string record_;  // reused for each record
  bool closed_ = false;
};

// CRC-32 (ISO-HDLC, zlib's crc32) of `bytes`, continuing from `crc` (0 to start).
uint32_t crc32(std::string_view bytes, uint32_t crc = 0);

}  // namespace rvc::transport::mcap
