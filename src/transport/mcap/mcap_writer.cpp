#include "transport/mcap/mcap_writer.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace rvc::transport::mcap {
namespace {

constexpr char kMagic[] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Opcodes of the records this writer emits (MCAP spec, "Records").
enum Op : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kStatistics = 0x0B,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

// All integers are little-endian; strings and byte arrays carry a uint32 length.
template <typename T>
void put_int(std::string& out, T v) {
  for (size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((static_cast<uint64_t>(v) >> (8 * i)) & 0xff));
}
void put_string(std::string& out, std::string_view s) {
  put_int<uint32_t>(out, static_cast<uint32_t>(s.size()));
  out.append(s);
}
// A record: opcode, content length (uint64), content.
void begin_record(std::string& out, Op op) {
  out.push_back(static_cast<char>(op));
  put_int<uint64_t>(out, 0);  // patched by end_record
}
void end_record(std::string& out, size_t begin) {
  const uint64_t len = out.size() - begin - 9;
  for (size_t i = 0; i < 8; ++i) out[begin + 1 + i] = static_cast<char>((len >> (8 * i)) & 0xff);
}

std::array<uint32_t, 256> make_crc_table() {
  std::array<uint32_t, 256> t{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
    t[i] = c;
  }
  return t;
}

}  // namespace

uint32_t crc32(std::string_view bytes, uint32_t crc) {
  static const std::array<uint32_t, 256> table = make_crc_table();
  crc = ~crc;
  for (unsigned char b : bytes) crc = table[(crc ^ b) & 0xff] ^ (crc >> 8);
  return ~crc;
}

McapWriter::McapWriter(std::FILE* file, std::string_view profile, std::string_view library) : file_(file) {
  emit(std::string_view(kMagic, sizeof kMagic));
  record_.clear();
  begin_record(record_, kHeader);
  put_string(record_, profile);
  put_string(record_, library);
  end_record(record_, 0);
  emit(record_);
}

void McapWriter::emit(std::string_view bytes) {
  if (bytes.empty()) return;
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    throw std::runtime_error(std::strerror(errno ? errno : EIO));
  offset_ += bytes.size();
  if (!closed_) data_crc_ = crc32(bytes, data_crc_);  // the data section: from the magic up to DataEnd
}

void McapWriter::schema_record(std::string& out, const Schema& s) {
  const size_t begin = out.size();
  begin_record(out, kSchema);
  put_int<uint16_t>(out, s.id);
  put_string(out, s.name);
  put_string(out, s.encoding);
  put_string(out, s.data);
  end_record(out, begin);
}

void McapWriter::channel_record(std::string& out, const Channel& c) {
  const size_t begin = out.size();
  begin_record(out, kChannel);
  put_int<uint16_t>(out, c.id);
  put_int<uint16_t>(out, c.schema_id);
  put_string(out, c.topic);
  put_string(out, c.message_encoding);
  std::string map;  // Map<string, string>: its byte length, then key/value pairs
  for (const auto& [k, v] : c.metadata) {
    put_string(map, k);
    put_string(map, v);
  }
  put_string(out, map);
  end_record(out, begin);
}

uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding, std::string_view data) {
  if (schemas_.size() >= 0xfffe) throw std::runtime_error("too many MCAP schemas");
  schemas_.push_back({static_cast<uint16_t>(schemas_.size() + 1), std::string(name), std::string(encoding),
                      std::string(data)});
  record_.clear();
  schema_record(record_, schemas_.back());
  emit(record_);
  return schemas_.back().id;
}

uint16_t McapWriter::add_channel(uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                 const std::map<std::string, std::string>& metadata) {
  if (channels_.size() >= 0xfffe) throw std::runtime_error("too many MCAP channels");
  channels_.push_back({static_cast<uint16_t>(channels_.size() + 1), schema_id, std::string(topic),
                       std::string(message_encoding), metadata});
  record_.clear();
  channel_record(record_, channels_.back());
  emit(record_);
  return channels_.back().id;
}

void McapWriter::write_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time, uint64_t publish_time,
                               std::string_view data) {
  record_.clear();
  begin_record(record_, kMessage);
  put_int<uint16_t>(record_, channel_id);
  put_int<uint32_t>(record_, sequence);
  put_int<uint64_t>(record_, log_time);
  put_int<uint64_t>(record_, publish_time);
  record_.append(data);
  end_record(record_, 0);
  emit(record_);
  if (message_count_ == 0 || log_time < start_time_) start_time_ = log_time;
  if (message_count_ == 0 || log_time > end_time_) end_time_ = log_time;
  ++message_count_;
  ++per_channel_[channel_id];
}

void McapWriter::close() {
  if (closed_) return;
  closed_ = true;  // from here on, bytes are not part of the data section's CRC
  record_.clear();
  begin_record(record_, kDataEnd);
  put_int<uint32_t>(record_, data_crc_);
  end_record(record_, 0);
  emit(record_);

  // Summary: one group per record type, each found again by a Summary Offset.
  const uint64_t summary_start = offset_;
  std::string summary;
  struct Group {
    Op op;
    uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](Op op, size_t from) {
    if (summary.size() > from) groups.push_back({op, summary_start + from, summary.size() - from});
  };
  size_t from = summary.size();
  for (const auto& s : schemas_) schema_record(summary, s);
  group(kSchema, from);
  from = summary.size();
  for (const auto& c : channels_) channel_record(summary, c);
  group(kChannel, from);
  from = summary.size();
  {
    const size_t begin = summary.size();
    begin_record(summary, kStatistics);
    put_int<uint64_t>(summary, message_count_);
    put_int<uint16_t>(summary, static_cast<uint16_t>(schemas_.size()));
    put_int<uint32_t>(summary, static_cast<uint32_t>(channels_.size()));
    put_int<uint32_t>(summary, 0);  // attachments
    put_int<uint32_t>(summary, 0);  // metadata records
    put_int<uint32_t>(summary, 0);  // chunks
    put_int<uint64_t>(summary, start_time_);
    put_int<uint64_t>(summary, end_time_);
    std::string counts;  // Map<uint16, uint64>
    for (const auto& [id, n] : per_channel_) {
      put_int<uint16_t>(counts, id);
      put_int<uint64_t>(counts, n);
    }
    put_string(summary, counts);
    end_record(summary, begin);
  }
  group(kStatistics, from);
  const uint64_t offsets_start = summary_start + summary.size();
  for (const auto& g : groups) {
    const size_t begin = summary.size();
    begin_record(summary, kSummaryOffset);
    put_int<uint8_t>(summary, g.op);
    put_int<uint64_t>(summary, g.start);
    put_int<uint64_t>(summary, g.length);
    end_record(summary, begin);
  }
  // Footer: the CRC covers the summary and offsets and the footer up to the CRC itself.
  summary.push_back(static_cast<char>(kFooter));
  put_int<uint64_t>(summary, 8 + 8 + 4);  // its length, written before the CRC that covers it
  put_int<uint64_t>(summary, summary_start);
  put_int<uint64_t>(summary, offsets_start);
  put_int<uint32_t>(summary, crc32(summary));
  summary.append(kMagic, sizeof kMagic);
  emit(summary);
  if (std::fflush(file_) != 0) throw std::runtime_error(std::strerror(errno ? errno : EIO));
}

}  // namespace rvc::transport::mcap
