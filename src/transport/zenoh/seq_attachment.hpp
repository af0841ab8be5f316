// The Zenoh attachment rvc puts on every sample (docs/zenoh.md, "Attachment"):
//
//   offset 0..7  seq    uint64, little-endian (1-based; 0 = unknown)
//   offset 8     flags  bit 0 = end of stream (payload empty, seq = last data seq)
//                       bits 1..7 reserved, sent as 0, ignored on receipt
//   offset 9..16 publisher  uint64, little-endian: a random id per rvc sink, so a
//                       subscriber counts sequence numbers per publisher (optional)
//
// Python: struct.pack("<QBQ", seq, flags, publisher), or "<QB" without the id.
// Receivers accept longer attachments (extra bytes ignored, room for later
// fields), read publisher 0 (unknown) from 9-byte ones, and treat shorter
// ones, or no attachment at all, as seq 0 without flags, so plain publishers
// still work.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace rvc::transport {

inline constexpr std::size_t kSeqAttachmentSize = 17;
inline constexpr std::size_t kSeqAttachmentMinSize = 9;  // without the publisher id
inline constexpr std::uint8_t kSeqFlagEos = 0x01;

struct SeqAttachment {
  std::uint64_t seq = 0;
  bool eos = false;
  std::uint64_t publisher = 0;
};

inline std::array<std::uint8_t, kSeqAttachmentSize> encode_seq_attachment(std::uint64_t seq, bool eos = false,
                                                                          std::uint64_t publisher = 0) {
  std::array<std::uint8_t, kSeqAttachmentSize> out{};
  for (std::size_t i = 0; i < 8; ++i) out[i] = static_cast<std::uint8_t>(seq >> (8 * i));
  out[8] = eos ? kSeqFlagEos : 0;
  for (std::size_t i = 0; i < 8; ++i) out[9 + i] = static_cast<std::uint8_t>(publisher >> (8 * i));
  return out;
}

inline SeqAttachment decode_seq_attachment(const std::uint8_t* data, std::size_t len) {
  SeqAttachment a;
  if (data == nullptr || len < 8) return a;
  for (std::size_t i = 0; i < 8; ++i) a.seq |= static_cast<std::uint64_t>(data[i]) << (8 * i);
  if (len >= kSeqAttachmentMinSize) a.eos = (data[8] & kSeqFlagEos) != 0;
  if (len >= kSeqAttachmentSize)
    for (std::size_t i = 0; i < 8; ++i) a.publisher |= static_cast<std::uint64_t>(data[9 + i]) << (8 * i);
  return a;
}

}  // namespace rvc::transport
